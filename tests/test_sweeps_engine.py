"""The sweep engine: results equal direct runs, failures are rows, resume runs only what is missing,
and a worker killed mid-sweep loses no row (two local worker processes)."""
import os
import signal

import numpy as np
import pandas as pd
import pytest

from plants import library
from bondgraph.numerics.simulation import simulate
import reproductions as scenarios
from sweeps import MetricError, StoreError, montecarlo_spec, run_sweep, spec_from_dict
from sweeps.runners import plan_runs

MSD = {"name": "mass-spring-damper", "stop_time": 20.0, "output_interval": 0.05}


def _grid_spec(**extra):
    return spec_from_dict({"model": dict(MSD), "vary": {"k": "linspace(2, 6, 3)", "m": "grid(0, 1)"},
                           "metrics": ["x.final", "x.max"], **extra})


def test_a_model_sweep_row_equals_the_model_simulated_directly(tmp_path):
    result = run_sweep(_grid_spec(), tmp_path, workers=0, progress=None, plots=False)
    table = pd.read_parquet(tmp_path / "runs.parquet")
    assert list(table["run_id"]) == list(range(6)) and table["param.k"].tolist() == [2.0, 2.0, 4.0, 4.0, 6.0, 6.0]
    eqs = library.build("mass-spring-damper").equations()
    for _, row in table[table["status"] == "ok"].iterrows():
        direct = simulate(eqs, (0.0, 20.0), params={"k": row["param.k"], "m": row["param.m"]}, output_interval=0.05)
        assert row["metric.x.final"] == direct["x"][-1] and row["metric.x.max"] == np.max(direct["x"])
    # m = 0 has no dynamics: recorded as failed with the simulator's message, and the sweep went on
    failed = table[table["status"] == "failed"]
    assert failed["param.m"].tolist() == [0.0, 0.0, 0.0] and result.n_failed == 3
    assert failed["error"].str.startswith("SimulationError: model 'mass_spring_damper': non-finite").all()
    assert failed["metric.x.final"].isna().all()
    assert result.summary["n_ok"] == 3 and result.summary["errors"] == {"SimulationError": 3}


def test_a_scenario_montecarlo_row_equals_the_scenario_run_directly(tmp_path):
    spec = montecarlo_spec("pam-ukf", samples=2, vary=["A1=normal(1,0.1)*nominal", "c_s=uniform(0.8,1.2)*nominal"],
                           quick=True, seed=11)
    result = run_sweep(spec, tmp_path, workers=0, progress=None)
    assert (result.table["status"] == "ok").all() and len(result.table) == 2
    row = result.table.iloc[1]
    direct = scenarios.run("pam-ukf", quick=True, params={"A1": row["param.A1"], "c_s": row["param.c_s"]},
                           seed=int(row["seed"]))
    assert row["metric.ukf.angle.I"] == direct["ukf"]["angle"]["I"]
    assert row["metric.model_only.torque.M"] == direct["model_only"]["torque"]["M"]
    nominal = scenarios.parameters("pam-ukf")["A1"].value
    assert 0.5 * nominal < row["param.A1"] < 1.5 * nominal and row["param.A1"] != nominal
    assert result.summary["metrics"][:2] == ["ukf.angle.I", "model_only.angle.I"]
    assert (tmp_path / "metrics_histograms.png").stat().st_size > 0 and (tmp_path / "sensitivity.png").exists()


def test_resume_runs_only_the_missing_rows(tmp_path):
    spec = _grid_spec()
    first = run_sweep(spec, tmp_path, workers=0, chunk_size=2, progress=None, plots=False)
    parts = sorted((tmp_path / "parts").glob("part-*.parquet"))
    assert len(parts) == 3
    parts[1].unlink()                     # as if the sweep had been killed before that chunk finished
    again = run_sweep(spec, tmp_path, resume=True, workers=0, progress=None, plots=False)
    assert (again.stats.n_run, again.stats.n_skipped) == (2, 4)
    pd.testing.assert_frame_equal(again.table.drop(columns=["started", "duration_s", "worker"]),
                                  first.table.drop(columns=["started", "duration_s", "worker"]))
    assert run_sweep(spec, tmp_path, resume=True, workers=0, progress=None, plots=False).stats.n_run == 0
    with pytest.raises(StoreError, match="pass --resume"):
        run_sweep(spec, tmp_path, workers=0, progress=None)
    with pytest.raises(StoreError, match="keys differ: seed"):
        run_sweep(_grid_spec(seed=1), tmp_path, resume=True, workers=0, progress=None)
    # the same laws in another order number the grid points otherwise: refused, not silently mixed
    reordered = spec_from_dict({"model": dict(MSD), "vary": {"m": "grid(0, 1)", "k": "linspace(2, 6, 3)"},
                                "metrics": ["x.final", "x.max"]})
    assert [r.params for r in plan_runs(reordered, {"m": 1, "k": 1})][:2] != \
        [r.params for r in plan_runs(spec, {"m": 1, "k": 1})][:2]
    with pytest.raises(StoreError, match=r"another order \(k, m before, m, k now\)"):
        run_sweep(reordered, tmp_path, resume=True, workers=0, progress=None)


def test_a_flush_interval_gathers_rows_into_fewer_files_losing_none(tmp_path):
    result = run_sweep(_grid_spec(), tmp_path, workers=0, chunk_size=1, progress=None, plots=False,
                       flush_interval_s=3600.0)
    assert result.stats.n_chunks == 6 and len(list((tmp_path / "parts").glob("part-*.parquet"))) == 1
    assert result.table["run_id"].tolist() == list(range(6))


def test_an_unknown_metric_stops_the_sweep_with_its_name(tmp_path):
    spec = montecarlo_spec("pam-ukf", samples=1, vary={"A1": "uniform(0.9, 1.1)*nominal"}, quick=True,
                           metrics=["ukf.angle.X"])
    with pytest.raises(MetricError, match="'ukf.angle.X'.*ukf.angle.I"):
        run_sweep(spec, tmp_path, workers=0, progress=None)


def test_a_worker_killed_mid_sweep_loses_no_row(tmp_path):
    """Through a scheduler address (as ``--scheduler tcp://...``), two worker processes, one SIGKILLed."""
    from distributed import Client, LocalCluster
    spec = spec_from_dict({"model": {**MSD, "stop_time": 60.0}, "vary": {"k": "uniform(2, 6)"}, "samples": 12,
                           "metrics": ["x.final"]})
    killed = []
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
            Client(cluster) as client:
        pids = list(client.run(os.getpid).values())

        def kill_one(rows):
            if not killed:                 # after the first chunk is on disk, SIGKILL a worker process
                os.kill(pids[0], signal.SIGKILL)
                killed.append(pids[0])

        result = run_sweep(spec, tmp_path / "dask", scheduler=cluster.scheduler_address, chunk_size=2,
                           progress=None, plots=False, on_chunk=kill_one)
    assert killed and len(result.table) == 12
    assert (result.table["status"] == "ok").all(), result.table[["run_id", "status", "error"]].to_string()
    serial = run_sweep(spec, tmp_path / "serial", workers=0, progress=None, plots=False)
    np.testing.assert_array_equal(result.table["metric.x.final"], serial.table["metric.x.final"])
    np.testing.assert_array_equal(result.table["param.k"], serial.table["param.k"])
