"""How many threads the compiled loops may use (bondgraph.numerics.threads)."""
import pytest

from bondgraph.numerics.threads import limited, worker_threads


def test_environment_and_limits(monkeypatch):
    monkeypatch.setenv("BONDCOSIM_THREADS", "3")
    assert worker_threads() == 3
    with limited(2):
        assert worker_threads() == 2
        with limited(5):                 # a limit never raises the count above the environment's
            assert worker_threads() == 3
        assert worker_threads() == 2
    assert worker_threads() == 3
    monkeypatch.setenv("BONDCOSIM_THREADS", "0")
    assert worker_threads() == 1
    monkeypatch.setenv("BONDCOSIM_THREADS", "two")
    with pytest.raises(ValueError, match="BONDCOSIM_THREADS.*'two'"):
        worker_threads()
    monkeypatch.delenv("BONDCOSIM_THREADS")
    assert worker_threads() >= 1


def test_a_sweep_chunk_runs_single_threaded():
    from sweeps.runners import RunSpec, run_chunk

    seen = []
    rows = run_chunk(lambda params, seed: seen.append(worker_threads()) or {"m": 1.0},
                     [RunSpec(run_id=0, params={"a": 1.0}, seed=0)])
    assert seen == [1] and rows[0]["status"] == "ok"
