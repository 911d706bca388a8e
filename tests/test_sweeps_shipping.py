"""Compiled C libraries are built once on the client and shipped: workers without a C compiler
(and with an empty cache) run model and scenario sweeps bit for bit like the serial run."""
import os

import numpy as np
import pytest
from distributed import Client, LocalCluster
from distributed.diagnostics.plugin import WorkerPlugin

from bondgraph.numerics import c_build
from sweeps import montecarlo_spec, run_sweep, spec_from_dict

needs_cc = pytest.mark.skipif(c_build.find_compiler() is None, reason="the client needs a C compiler")


class NoCompiler(WorkerPlugin):
    """Makes a worker process a node without a compiler: empty PATH, no $CC, an empty cache,
    and the compiler call itself refused (counted, should it ever be reached)."""

    name = "no-compiler"

    def __init__(self, root):
        self.root = str(root)

    def setup(self, worker):
        from bondgraph.numerics import c_build as build
        from bondgraph.errors import CompilationError
        empty = os.path.join(self.root, f"path-{os.getpid()}")
        os.makedirs(empty, exist_ok=True)
        os.environ["PATH"] = empty
        os.environ.pop("CC", None)
        os.environ["BONDCOSIM_CACHE"] = os.path.join(self.root, f"cache-{os.getpid()}")
        build.ATTEMPTS = []

        def refuse(cmd):
            build.ATTEMPTS.append(cmd)
            raise CompilationError(f"a worker tried to compile: {cmd}")
        build._run_compiler = refuse


def _worker_state():
    from bondgraph.numerics import c_build as build
    from bondgraph.numerics import c_shipped
    return {"pid": os.getpid(), "compiler": build.find_compiler(), "attempts": len(getattr(build, "ATTEMPTS", [None])),
            "libraries": len(set(c_shipped.installed().values())),
            "from_shipped_dir": all(str(p).startswith(str(c_shipped.shipped_dir()))
                                    for p in c_shipped.installed().values())}


@pytest.fixture
def no_compiler_client(tmp_path):
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
            Client(cluster) as client:
        client.register_plugin(NoCompiler(tmp_path / "workers"))
        assert all(s["compiler"] is None for s in client.run(_worker_state).values())
        yield client


@needs_cc
def test_workers_without_a_compiler_run_shipped_kernels_bit_for_bit(tmp_path, monkeypatch, no_compiler_client):
    monkeypatch.setenv("BONDCOSIM_CACHE", str(tmp_path / "client-cache"))   # nothing compiled before
    compiled = []
    run_compiler = c_build._run_compiler
    monkeypatch.setattr(c_build, "_run_compiler", lambda cmd: (compiled.append(cmd), run_compiler(cmd)))
    spec = spec_from_dict({"model": {"name": "mass-spring-damper", "stop_time": 20.0, "output_interval": 0.05},
                           "vary": {"k": "uniform(2, 6)", "b": "uniform(0.1, 1)"}, "samples": 8,
                           "metrics": ["x.final", "x.max", "x.rms"]})
    serial = run_sweep(spec, tmp_path / "serial", workers=0, progress=None, plots=False)
    # the model's two libraries (f/h/rk4 and the Jacobians of the stiff solver), each compiled once, here
    assert len(compiled) == 2
    # loaded in this process already (so no longer built or looked up): recorded and shipped all the same
    shipped = run_sweep(spec, tmp_path / "dask", client=no_compiler_client, chunk_size=2, progress=None, plots=False)
    assert len(compiled) == 2
    assert (shipped.table["status"] == "ok").all() and len(shipped.table) == 8
    for column in ("param.k", "param.b", "metric.x.final", "metric.x.max", "metric.x.rms"):
        np.testing.assert_array_equal(shipped.table[column], serial.table[column])
    workers = no_compiler_client.run(_worker_state)
    ran = set(shipped.table["worker"].str.rsplit(":", n=1).str[1].astype(int))
    assert ran <= {state["pid"] for state in workers.values()}
    for state in workers.values():
        assert state["compiler"] is None and state["attempts"] == 0
        if state["pid"] in ran:
            assert state["libraries"] == 2 and state["from_shipped_dir"]


@needs_cc
def test_a_scenario_montecarlo_runs_on_workers_without_a_compiler(tmp_path, no_compiler_client):
    spec = montecarlo_spec("pam-ukf", samples=2, vary=["A1=normal(1,0.1)*nominal"], quick=True, seed=3)
    serial = run_sweep(spec, tmp_path / "serial", workers=0, progress=None, plots=False)
    shipped = run_sweep(spec, tmp_path / "dask", client=no_compiler_client, chunk_size=1, progress=None,
                        plots=False)
    assert (shipped.table["status"] == "ok").all(), shipped.table["error"].tolist()
    for column in ("param.A1", "seed", "metric.ukf.angle.I", "metric.model_only.angle.I", "metric.ukf.torque.M"):
        np.testing.assert_array_equal(shipped.table[column], serial.table[column])
    for state in no_compiler_client.run(_worker_state).values():
        assert state["compiler"] is None and state["attempts"] == 0
        # the bridge to the FMUs, and the model and UKF kernels of the free and the locked joint
        assert state["libraries"] in (0, 5) and state["from_shipped_dir"]
