"""Sweep scaling: N pam-ukf runs serially, on a local Dask cluster, and on a separate
``dask scheduler`` with ``dask worker`` processes on localhost; and the Dask overhead per task.

Set-up (not timed): the spec (``pam-ukf``, 13 segments of ``--segment`` s, A1, A2, c_s,
mu_p uniform within +-20 % of the rig's values, fixed seed).  Timed, each in
a fresh results directory, wall clock:

(a) serial: ``run_sweep(workers=0)`` in this process;
(b) local: ``run_sweep(workers=K)``, cluster start-up and shut-down included
    (the column ``setup`` shows the start-up alone);
(c) external: ``dask scheduler`` and K ``dask worker --nthreads 1`` processes
    started here first (not timed), then ``run_sweep(scheduler=ADDRESS)``;
(d) overhead: M no-op tasks through the local cluster's scheduler (per-task
    round trip), and the sweep's own overhead,
    ``(wall x workers - sum of run times) / tasks``, which also counts the
    workers' warm-up (imports, deriving the model) and the idle tail;
(e) chunking: `--model-runs` short runs (``mass-spring-damper``, 20 s, tens of
    ms each) on the local cluster, one run per task against the automatic chunk
    size: the overhead per run, as a fraction of the run time;
(f) shipping: the runner's pickled size (what each worker fetches once: FMUs
    and compiled C libraries), the client's preparation (FMU export and the
    recording run), and in a fresh process with an empty cache: unpickling the
    runner and installing and loading its shipped libraries, against generating
    and compiling them there.

The machine load (1-min load average) is printed before and after each
measurement: on a shared machine the speed-up is bounded by the free cores, not
by the code.  ``docs/scaling.md`` records a run and extrapolates to 100 nodes.

Run:  python benchmarks/sweep_scaling.py [--runs 200] [--segment 0.3] [--workers 2] [--no-external] [--model-runs 400]
      [--no-shipping]
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from sweeps import montecarlo_spec, run_sweep  # noqa: E402

VARY = {"A1": "uniform(0.8, 1.2)*nominal", "A2": "uniform(0.8, 1.2)*nominal",
        "c_s": "uniform(0.8, 1.2)*nominal", "mu_p": "uniform(0.8, 1.2)*nominal"}


def setup(runs: int, segment: float):
    """The benchmark's spec: `runs` pam-ukf runs of 13 segments of `segment` s."""
    return montecarlo_spec("pam-ukf", samples=runs, vary=VARY, fixed={"segment_s": segment}, seed=1,
                           metrics=["ukf.angle.I", "model_only.angle.I"])


def _load() -> float:
    return os.getloadavg()[0]


def _timed(label, fn) -> dict:
    before, start = _load(), time.perf_counter()
    result = fn()
    wall = time.perf_counter() - start
    s = result.stats
    row = {"engine": label, "wall_s": wall, "setup_s": s.setup_s, "runs_wall_s": s.wall_s, "busy_s": s.busy_s,
           "workers": s.n_workers, "tasks": s.n_chunks, "failed": s.n_failed, "load_before": before,
           "load_after": _load()}
    row["overhead_per_task_ms"] = 1e3 * max(0.0, s.wall_s * s.n_workers - s.busy_s) / max(s.n_chunks, 1)
    # each worker's first run (by start time) over its median: imports, derivation, C kernels
    by_worker = result.table.sort_values("started").groupby("worker")["duration_s"]
    row["warmup_s"] = float((by_worker.first() - by_worker.median()).mean())
    return row


def chunking(n_runs: int, workers: int) -> list:
    """(e): the same short-run sweep with one run per task and with the automatic chunks."""
    from distributed import Client, LocalCluster

    from sweeps import spec_from_dict
    spec = spec_from_dict({"model": {"name": "mass-spring-damper", "stop_time": 20.0, "output_interval": 0.05},
                           "vary": {"k": "uniform(2, 6)", "b": "uniform(0.2, 0.6)"}, "samples": n_runs,
                           "metrics": ["x.final"]})
    rows = []
    with tempfile.TemporaryDirectory() as tmp, \
            LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
            Client(cluster) as client:
        run_sweep(spec, Path(tmp) / "warm", client=client, chunk_size=8, plots=False, progress=None)  # warm workers
        for label, size in (("1 run/task", 1), ("auto", None)):
            before = _load()
            s = run_sweep(spec, Path(tmp) / label.replace("/", "-"), client=client, chunk_size=size, plots=False,
                          progress=None).stats
            overhead = max(0.0, s.wall_s * s.n_workers - s.busy_s)
            rows.append({"chunks": label, "chunk_size": s.chunk_size, "tasks": s.n_chunks, "wall_s": s.wall_s,
                         "mean_run_ms": 1e3 * s.busy_s / n_runs, "overhead_per_run_ms": 1e3 * overhead / n_runs,
                         "overhead_fraction": overhead / s.busy_s, "load_before": before})
    return rows


_FRESH = """
import ctypes, pickle, sys, time
start = time.perf_counter()
runner = pickle.loads(open(sys.argv[1], "rb").read())
unpickled = time.perf_counter()
from bondgraph.numerics import c_shipped
runner.kernels.install()
libs = [ctypes.CDLL(str(p)) for p in set(c_shipped.installed().values())]
print(unpickled - start, time.perf_counter() - unpickled, len(libs))
"""

_FIRST_RUN = """
import pickle, sys, time
shipped = pickle.loads(open(sys.argv[1], "rb").read())
if sys.argv[2] == "compile":
    shipped.kernels = None        # as before shipping: this process derives, generates and compiles
start = time.perf_counter()
shipped({}, 0)
print(time.perf_counter() - start)
"""


def shipping(spec) -> dict:
    """(f): what a worker receives, and what loading it costs against compiling on the node."""
    import cloudpickle

    from sweeps.runners import make_runner
    runner = make_runner(spec)
    before, start = _load(), time.perf_counter()
    runner.prepare()
    prepare_s = time.perf_counter() - start
    with tempfile.TemporaryDirectory() as tmp:
        blob = Path(tmp) / "runner.pkl"
        blob.write_bytes(cloudpickle.dumps(runner))
        env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(Path(__file__).resolve().parent.parent),
                                                           os.environ.get("PYTHONPATH", "")]))

        def fresh(script, *args):       # a new process with an empty C cache, like a fresh node's worker
            env["BONDCOSIM_CACHE"] = tempfile.mkdtemp(dir=tmp)
            return subprocess.run([sys.executable, "-c", script, str(blob), *args], env=env, capture_output=True,
                                  text=True, check=True).stdout.split()

        unpickle, install = fresh(_FRESH)[:2]
        compiling, = fresh(_FIRST_RUN, "compile")
        shipped, = fresh(_FIRST_RUN, "ship")
        return {"runner_bytes": blob.stat().st_size, "fmu_bytes": sum(len(b) for b in runner.fmus.values()),
                "kernel_bytes": runner.kernels.nbytes, "libraries": len(runner.kernels.libraries),
                "prepare_s": prepare_s, "unpickle_s": float(unpickle), "install_load_s": float(install),
                "first_run_compiling_s": float(compiling), "first_run_shipped_s": float(shipped),
                "load_before": before, "load_after": _load()}


def _noop(i):
    return i


def null_task_overhead(workers: int, n: int) -> dict:
    """Per-task round trip of `n` no-op tasks through a local cluster of `workers` processes."""
    from distributed import Client, LocalCluster
    with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
            Client(cluster) as client:
        client.gather(client.map(_noop, range(workers), pure=False))       # warm
        before, start = _load(), time.perf_counter()
        client.gather(client.map(_noop, range(n), pure=False))
        wall = time.perf_counter() - start
    return {"tasks": n, "wall_s": wall, "per_task_ms": 1e3 * wall / n, "tasks_per_s": n / wall,
            "load_before": before}


def _dask_command(*args) -> list:
    exe = shutil.which("dask")
    return [exe, *args] if exe else [sys.executable, "-m", "dask", *args]


def external_cluster(workers: int, directory: Path):
    """Start ``dask scheduler`` and `workers` ``dask worker`` processes; returns (address, processes)."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(Path(__file__).resolve().parent.parent),
                                                       os.environ.get("PYTHONPATH", "")]))
    file = directory / "scheduler.json"
    log = open(directory / "dask.log", "w")
    procs = [subprocess.Popen(_dask_command("scheduler", "--scheduler-file", str(file), "--port", "0",
                                            "--dashboard-address", ":0"), env=env, stdout=log, stderr=log)]
    for _ in range(60):
        if file.exists():
            break
        time.sleep(0.5)
    for _ in range(workers):
        procs.append(subprocess.Popen(_dask_command("worker", "--scheduler-file", str(file), "--nthreads", "1",
                                                    "--nworkers", "1", "--no-dashboard"), env=env, stdout=log,
                                      stderr=log))
    address = json.loads(file.read_text())["address"]
    from distributed import Client
    with Client(address) as client:
        client.wait_for_workers(workers, timeout=120)
    return address, procs


def main(runs: int = 200, segment: float = 0.3, workers: int = 2, external: bool = True, null_tasks: int = 1000,
         json_path=None, model_runs: int = 400, ship: bool = True) -> dict:
    spec = setup(runs, segment)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        rows.append(_timed("serial", lambda: run_sweep(spec, tmp / "serial", workers=0, plots=False,
                                                       progress=None)))
        rows.append(_timed(f"local:{workers}", lambda: run_sweep(spec, tmp / "local", workers=workers, plots=False,
                                                                 progress=None)))
        if external:
            address, procs = external_cluster(workers, tmp)
            try:
                rows.append(_timed(f"external:{workers}", lambda: run_sweep(spec, tmp / "external",
                                                                            scheduler=address, plots=False,
                                                                            progress=None)))
            finally:
                for p in reversed(procs):
                    p.terminate()
                for p in procs:
                    p.wait(timeout=30)
        null = null_task_overhead(workers, null_tasks)
    chunks = chunking(model_runs, workers) if model_runs else []
    ship = shipping(spec) if ship else None
    serial = rows[0]["wall_s"]
    print(f"{runs} pam-ukf runs of 13 x {segment} s on {os.cpu_count()} cores")
    print(f"{'engine':<12} {'wall s':>8} {'setup s':>8} {'speed-up':>9} {'tasks':>6} {'ovh/task ms':>12} "
          f"{'warm-up s':>10} {'load before':>12} {'after':>6}")
    for r in rows:
        print(f"{r['engine']:<12} {r['wall_s']:>8.1f} {r['setup_s']:>8.2f} {serial / r['wall_s']:>9.2f} "
              f"{r['tasks']:>6} {r['overhead_per_task_ms']:>12.1f} {r['warmup_s']:>10.2f} "
              f"{r['load_before']:>12.2f} {r['load_after']:>6.2f}")
    print(f"mean run time (serial): {rows[0]['busy_s'] / runs:.3f} s; no-op task round trip through the local "
          f"scheduler: {null['per_task_ms']:.2f} ms ({null['tasks_per_s']:.0f} tasks/s, "
          f"load {null['load_before']:.2f})")
    for c in chunks:
        print(f"{model_runs} model runs, {c['chunks']:<10} (chunk {c['chunk_size']:>3}, {c['tasks']:>4} tasks): "
              f"wall {c['wall_s']:.2f} s, run {c['mean_run_ms']:.1f} ms, overhead {c['overhead_per_run_ms']:.1f} ms "
              f"per run = {100 * c['overhead_fraction']:.1f} % of run time (load {c['load_before']:.2f})")
    if ship is None:
        print("shipping: not measured (--no-shipping)")
    else:
        print(f"shipped once per worker: runner {ship['runner_bytes'] / 1e3:.0f} kB pickled (FMUs "
              f"{ship['fmu_bytes'] / 1e3:.0f} kB, {ship['libraries']} C libraries {ship['kernel_bytes'] / 1e3:.0f} "
              f"kB); client preparation {ship['prepare_s']:.2f} s; in a fresh process: unpickle "
              f"{ship['unpickle_s']:.2f} s, install + load the libraries {1e3 * ship['install_load_s']:.1f} ms; first "
              f"run with the libraries shipped {ship['first_run_shipped_s']:.2f} s, compiling them (empty cache) "
              f"{ship['first_run_compiling_s']:.2f} s (load {ship['load_before']:.2f} -> {ship['load_after']:.2f})")
    result = {"runs": runs, "segment_s": segment, "cores": os.cpu_count(), "rows": rows, "null_tasks": null,
              "chunking": chunks, "shipping": ship}
    if json_path:
        Path(json_path).write_text(json.dumps(result, indent=1))
    return result


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=200)
    ap.add_argument("--segment", type=float, default=0.3, help="s per profile segment (13 segments per run)")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--null-tasks", type=int, default=1000)
    ap.add_argument("--no-external", action="store_true", help="skip the dask scheduler / dask worker processes")
    ap.add_argument("--model-runs", type=int, default=400, help="short runs for the chunking comparison (0: skip)")
    ap.add_argument("--json", default=None, help="also write the numbers to this JSON file")
    ap.add_argument("--no-shipping", action="store_true", help="skip (f), the shipping measurement")
    a = ap.parse_args()
    main(a.runs, a.segment, a.workers, not a.no_external, a.null_tasks, a.json, a.model_runs, not a.no_shipping)
