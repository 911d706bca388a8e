"""An electrochemical plant no part of the project was built around: a lithium-ion cell written as a
user would (``tests/data/models/cell.py``: a Thevenin model without its RC pair, the open-circuit
voltage ``E0 + q/Cb`` a linear fit of the OCV curve, the charging current a flow source), its truth
the tests' own RK4 (``tests/msd_truth.py``), 1 Hz for an hour of held current levels, 1 mV noise and
resolution.  A current sensor's bias had been answered as a hardening of the charge storage, with a
held-out error 26 % higher than the nominal's, and a 5 % scale error of it as nothing: the
vocabulary neither shifted nor scaled an input.  Its polarisation (the RC pair the model leaves
out) had been answered as a series resistance, its voltage hysteresis as a 127 s RC pair (Dahl's
law was offered at mechanical junctions only)."""
from pathlib import Path

import numpy as np
import pytest

from bondgraph.numerics import simulate
from diagnosis.catalogue import candidates
from diagnosis.diagnose import diagnose
from diagnosis.place import Place
from msd_truth import rk4_states
from plants import load

MODEL = Path(__file__).parent / "data" / "models" / "cell.py"
QCAP, E0, R0, Q0 = 9000.0, 3.3, 0.05, 4500.0      # C (2.5 Ah), V, Ohm, C (half charged)
SLOPE = 0.8                                        # V: the OCV's rise from empty to full
BIAS = 0.05                                        # A: the current sensor reads this much high
SCALE = 0.95                                       # the cell takes this share of the current recorded
R1, C1 = 0.01, 3000.0                              # Ohm, F: the polarisation pair (30 s)
M, Q_TURN = 0.015, 180.0                           # V, C: the voltage hysteresis and the charge it turns over in


def _currents(n, rng):
    """Charging currents (A) held 20-180 s, turned round where the charge would leave 20-80 %."""
    out, k, soc = np.zeros(n), 0, 0.5
    while k < n:
        hold = int(rng.uniform(20, 180))
        level = float(rng.choice([-2.5, -1.25, 0.0, 1.25, 2.5]))
        if not 0.2 < soc + level * hold / QCAP < 0.8:
            level = -level
        out[k:k + hold] = level
        soc += level * min(hold, n - k) / QCAP
        k += hold
    return out


def _recording(path, effect, seed=1):
    rng = np.random.default_rng(seed)
    t = np.arange(3601.0)
    recorded = _currents(t.size, rng)
    current = recorded - (BIAS if effect == "bias" else 0.0)      # what the cell really takes
    current = current * (SCALE if effect == "gain" else 1.0)

    def rate(x, i):
        q, v1, vh = x                   # charge, C; the pair's voltage, V; the hysteresis's voltage, V
        pair = (i - v1 / R1) / C1 if "rc" in effect else 0.0
        # Plett's one-state hysteresis: M h, dh/dq = (sgn(i) - h)/Q_turn
        turn = (M * i - abs(i) * vh) / Q_TURN if "hysteresis" in effect else 0.0
        return np.array([i, pair, turn])

    x = rk4_states(rate, t, current, substeps=2, x0=(Q0, 0.0, 0.0))
    V = E0 + SLOPE * x[:, 0] / QCAP + R0 * current + x[:, 1] + x[:, 2]
    y = np.round((V + rng.normal(0.0, 1e-3, t.size)) / 1e-3) * 1e-3
    path.write_text("t,I,V\n" + "\n".join(f"{t[i]:g},{recorded[i]:g},{y[i]:.4f}" for i in range(t.size)) + "\n")
    return path


def _diagnose(path, max_effects=1):
    return diagnose(str(MODEL), str(path), inputs=["I=I"], outputs=["V=V:V"], max_effects=max_effects)


def test_an_input_offset_shifts_what_the_plant_receives():
    """The candidate's graph against the closed form of a cell charged at I + delta."""
    cell = load(str(MODEL))
    (cand,) = [c for c in candidates(cell, Place("input", "I")) if c.kind == "input_offset"]
    shifted = cand.build(cell, {cand.params[0].name: -0.2})
    t = np.linspace(0.0, 100.0, 11)
    run = simulate(shifted, (0.0, 100.0), inputs={"I": 1.5}, output_interval=10.0, rtol=1e-10, atol=1e-10)
    q = Q0 + (1.5 - 0.2) * t
    assert run.t == pytest.approx(t)
    assert run["V"] == pytest.approx(E0 + q * SLOPE / QCAP + R0 * 1.3, abs=1e-9)


def test_a_current_sensors_bias_is_an_input_offset_the_drift_open_loop_tells(tmp_path):
    data = _diagnose(_recording(tmp_path / "bias.csv", "bias")).to_json()
    (effect,) = data["missing_physics"]
    assert (effect["kind"], effect["attached_to"]) == ("input_offset", "input I")
    assert effect["parameters"]["offset_I"] == pytest.approx(-BIAS, rel=0.02)
    # the nominal drifts (its charge integrates the bias): judged on segments, and open loop the
    # offset takes out nearly all of the drift
    assert data["fit"]["judge"] == "segments"
    loop = data["fit"]["open_loop"]
    assert loop["improved"]["V"] < 0.1 * loop["nominal"]["V"]


def test_a_resistance_outside_mechanics_is_said_in_its_domains_words_and_unit():
    cell = load(str(MODEL))
    (cand,) = [c for c in candidates(cell, Place("junction", "cell")) if c.kind == "viscous_friction"]
    assert cand.params[0].unit == "Ohm"
    words = cand.explain({cand.params[0].name: 0.0075})
    assert "series resistance" in words and "0.0075 Ohm" in words and "motion" not in words


def test_a_relaxing_branch_charges_with_its_time_constant():
    """The candidate's graph against the closed form of an RC pair charged by a current step."""
    cell = load(str(MODEL))
    (cand,) = [c for c in candidates(cell, Place("junction", "cell")) if c.kind == "relaxation"]
    r, tau = (spec.name for spec in cand.params)
    relaxed = cand.build(cell, {r: 0.02, tau: 40.0})
    run = simulate(relaxed, (0.0, 200.0), inputs={"I": 2.0}, output_interval=20.0, rtol=1e-11, atol=1e-11)
    t = np.asarray(run.t)
    ohmic = E0 + (Q0 + 2.0 * t) * SLOPE / QCAP + R0 * 2.0
    assert run["V"] == pytest.approx(ohmic + 0.02 * 2.0 * (1.0 - np.exp(-t / 40.0)), abs=1e-9)


def test_a_cells_polarisation_is_a_relaxation_with_its_rc_pair(tmp_path):
    report = _diagnose(_recording(tmp_path / "rc.csv", "rc"))
    data = report.to_json()
    (effect,) = data["missing_physics"]
    assert (effect["kind"], effect["attached_to"]) == ("relaxation", "junction cell")
    assert effect["parameters"]["R_relax_cell"] == pytest.approx(R1, rel=0.03)
    assert effect["parameters"]["tau_relax_cell"] == pytest.approx(R1 * C1, rel=0.03)
    assert "RC pair" in effect["explanation"] and "Ohm" in effect["explanation"]
    assert data["fit"]["improved"]["V"] < 0.1 * data["fit"]["nominal"]["V"]


def test_a_current_sensors_scale_error_is_an_input_gain(tmp_path):
    data = _diagnose(_recording(tmp_path / "gain.csv", "gain")).to_json()
    (effect,) = data["missing_physics"]
    assert (effect["kind"], effect["attached_to"]) == ("input_gain", "input I")
    assert effect["parameters"]["gain_I"] == pytest.approx(SCALE, rel=0.005)
    assert data["fit"]["improved"]["V"] < 0.5 * data["fit"]["nominal"]["V"]


def test_a_cells_voltage_hysteresis_is_a_dahl_law_in_the_charge(tmp_path):
    """Plett's one-state hysteresis, M h with dh/dq = (sgn(i) - h)/Q_turn, is Dahl's law with
    F_h = M and sigma = M/Q_turn."""
    data = _diagnose(_recording(tmp_path / "hysteresis.csv", "hysteresis")).to_json()
    (effect,) = data["missing_physics"]
    assert (effect["kind"], effect["attached_to"]) == ("hysteresis", "junction cell")
    assert effect["parameters"]["Fh_cell"] == pytest.approx(M, rel=0.02)
    assert effect["parameters"]["sigma_dahl_cell"] == pytest.approx(M / Q_TURN, rel=0.03)
    assert "voltage hysteresis" in effect["explanation"] and "180 C" in effect["explanation"]
    assert data["fit"]["improved"]["V"] < 0.2 * data["fit"]["nominal"]["V"]


def test_a_cells_pair_and_hysteresis_together_are_the_enhanced_self_correcting_model(tmp_path):
    """Both at once (Plett's enhanced self-correcting cell model, less its OCV curve): two rounds
    name the pair and the hysteresis, each with its values."""
    data = _diagnose(_recording(tmp_path / "both.csv", "rc+hysteresis"), max_effects=2).to_json()
    found = {e["kind"]: e for e in data["missing_physics"]}
    assert set(found) == {"relaxation", "hysteresis"}
    assert {e["attached_to"] for e in found.values()} == {"junction cell"}
    assert found["relaxation"]["parameters"]["R_relax_cell"] == pytest.approx(R1, rel=0.03)
    assert found["relaxation"]["parameters"]["tau_relax_cell"] == pytest.approx(R1 * C1, rel=0.03)
    assert found["hysteresis"]["parameters"]["Fh_cell"] == pytest.approx(M, rel=0.03)
    assert data["fit"]["improved"]["V"] < 0.1 * data["fit"]["nominal"]["V"]
