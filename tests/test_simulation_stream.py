"""Streaming a simulation to CSV (bondgraph/numerics/simulation_stream.py, ``simulate --stream``).

Reference: the same simulation in one call (bondgraph.numerics.simulation.simulate); fixed-step models
must agree to rounding, adaptive ones within the solver's tolerances.
"""
from __future__ import annotations

import numpy as np
import pytest

from bondcosim.cli import main
from plants import library
from bondgraph.numerics import simulate
from bondgraph.errors import ArgumentError, OutputTooLargeError, UnknownNameError
from bondgraph.numerics.results import SimulationResult
from bondgraph.numerics.simulation_stream import simulate_to_csv


def test_fixed_step_pam_in_segments_equals_one_run(tmp_path):
    graph = library.build("pam")   # held Kikuuwe friction, fixed-step RK4
    inputs = {"u1": "5 + 3*sin(20*t)", "u2": 4.0}
    one = simulate(graph, (0.0, 0.05), inputs=inputs, output_interval=1e-3)
    done = simulate_to_csv(graph, (0.0, 0.05), tmp_path / "pam.csv", output_interval=1e-3, inputs=inputs,
                           chunk_samples=7)
    assert done == {"samples": 51, "segments": 8, "path": str(tmp_path / "pam.csv")}
    streamed = SimulationResult.from_csv(tmp_path / "pam.csv")
    assert streamed.names == one.names and streamed.units == one.units
    np.testing.assert_allclose(streamed.t, one.t, rtol=0, atol=1e-15)
    for name in one.names:
        # to rounding: the segments rebuild the time grid from their own start (t differs by ~1e-16 s)
        np.testing.assert_allclose(streamed[name], one[name], rtol=1e-9, atol=1e-9 * np.abs(one[name]).max())


def test_adaptive_rlc_in_segments_agrees_within_tolerance(tmp_path):
    graph = library.build("rlc")
    one = simulate(graph, (0.0, 0.02), output_interval=1e-4)
    simulate_to_csv(graph, (0.0, 0.02), tmp_path / "rlc.csv", output_interval=1e-4, chunk_samples=33)
    streamed = SimulationResult.from_csv(tmp_path / "rlc.csv")
    for name in one.names:
        scale = max(np.abs(one[name]).max(), 1e-12)
        np.testing.assert_allclose(streamed[name] / scale, one[name] / scale, atol=1e-6)


def test_held0_continues_a_run_and_is_checked():
    graph = library.build("pam")
    with pytest.raises(ArgumentError, match=r"held0: expected shape \(1,\)"):
        simulate(graph, (0.0, 0.01), held0=[0.0, 1.0])
    with pytest.raises(UnknownNameError, match="unknown held variable 'T_x'"):
        simulate(graph, (0.0, 0.01), held0={"T_x": 0.0})
    r = simulate(graph, (0.0, 0.002), held0={"T_f": 0.01}, output_interval=1e-3)
    assert r["T_f"][0] == 0.01


def test_disk_too_small_is_refused_naming_sizes(tmp_path):
    with pytest.raises(OutputTooLargeError, match=r"1e\+15 samples of 6 signals need about .* GiB of CSV"):
        simulate_to_csv(library.build("rlc"), (0.0, 1e9), tmp_path / "o.csv", output_interval=1e-6)
    assert not (tmp_path / "o.csv").exists()


def test_cli_stream(tmp_path, capsys):
    out = tmp_path / "o.csv"
    assert main(["simulate", "rlc", "--stop-time", "0.01", "--output-interval", "1e-4", "-o", str(out),
                 "--stream"]) == 0
    assert "101 samples" in capsys.readouterr().out
    assert SimulationResult.from_csv(out).t.size == 101
    assert main(["simulate", "rlc", "--stop-time", "0.01", "-o", str(out), "--stream"]) == 1
    assert "--stream needs --output-interval" in capsys.readouterr().err
