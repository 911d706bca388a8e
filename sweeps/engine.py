"""Run a sweep's runs in chunks: serially, on a local Dask cluster, or on any running Dask scheduler.

The client (this process) plans the runs, skips those already on disk
(``--resume``), builds the runner once (:mod:`sweeps.runners`) and ships it to
each worker once: it is the result of one small task that every chunk task
depends on, so each worker fetches it once from a peer, and if the worker
holding it dies the scheduler recomputes it.  Chunk tasks return their rows;
the client writes each chunk as its own Parquet part the moment it arrives
(:mod:`sweeps.store`).

Losing nothing:

- a run that raises is a ``failed`` row with its error text (:func:`~sweeps.runners.run_chunk`);
- a worker killed mid-chunk: the scheduler reassigns its unfinished chunks to
  the other workers (Dask's ``distributed.scheduler.allowed-failures``, 3 by
  default); finished chunks are on disk already.  A chunk whose worker died on
  every attempt (``KilledWorker``: the run itself crashes the process) is written
  as failed rows naming that;
- a killed client: every chunk written is kept; ``resume=True`` runs only the missing run ids.

Chunk size (:func:`_chunk_size`): tasks of at least :data:`MIN_TASK_S` (a
scenario run takes 0.3 s or more, so one run per task; a model run tens of ms,
so about 17), larger on big clusters so that the scheduler sees at most
:data:`SCHEDULER_RATE` tasks per second, and capped so that every worker gets
about four chunks (load balance at the end of the sweep).  ``benchmarks/sweep_scaling.py``
measures the overhead (``docs/scaling.md``).
"""
from __future__ import annotations

import logging
import math
import os
import time
from dataclasses import dataclass

from .errors import EngineError, MetricError
from .progress import ProgressBar
from .runners import run_chunk

__all__ = ["execute", "ExecutionStats", "chunked", "default_workers"]


@dataclass(frozen=True)
class ExecutionStats:
    """What one session did.

    Attributes
    ----------
    n_planned, n_skipped, n_run, n_failed : int
        Runs in the sweep, found on disk, run now, failed now.
    n_chunks : int
    chunk_size : int
    engine : str
        ``"serial"``, ``"local:K"`` or the scheduler address.
    n_workers : int
    wall_s : float, s
        Wall time of the session's runs (after the cluster was up and the runner built).
    busy_s : float, s
        Sum of the runs' own durations.
    setup_s : float, s
        Starting or reaching the cluster.
    """

    n_planned: int
    n_skipped: int
    n_run: int
    n_failed: int
    n_chunks: int
    chunk_size: int
    engine: str
    n_workers: int
    wall_s: float
    busy_s: float
    setup_s: float


def default_workers() -> int:
    """One worker process per core."""
    return os.cpu_count() or 1


def chunked(runs: list, size: int) -> list:
    """`runs` cut into consecutive lists of `size` (the last may be shorter)."""
    return [runs[i:i + size] for i in range(0, len(runs), size)]


#: Tasks per second one Dask scheduler is asked to handle at most, whatever the cluster's size
#: (it manages a few thousand; ``docs/scaling.md``).
SCHEDULER_RATE = 250.0
#: Shortest task wanted, s: against a few ms of Dask overhead per task, under 1 %.
MIN_TASK_S = 0.5


def _chunk_size(requested, runner, n_todo: int, n_workers: int) -> int:
    r"""Runs per task.

    With a run time :math:`t_r` (the runner's ``run_time_hint_s``) and W workers, a task of c runs
    lasts :math:`c t_r` and the scheduler sees :math:`W / (c t_r)` tasks per second, so

    .. math:: c = \max\left(\lceil T_{min} / t_r \rceil, \lceil W / (R\, t_r) \rceil\right)

    with :data:`MIN_TASK_S` and :data:`SCHEDULER_RATE`; then capped at
    :math:`\lceil n / 4W \rceil` so that every worker gets about four chunks.
    """
    if requested is not None:
        if int(requested) < 1:
            raise EngineError("", f"chunk size must be >= 1, got {requested!r}")
        return int(requested)
    t_run = float(getattr(runner, "run_time_hint_s", MIN_TASK_S))
    wanted = max(math.ceil(MIN_TASK_S / t_run), math.ceil(n_workers / (SCHEDULER_RATE * t_run)))
    balance = math.ceil(n_todo / (4 * max(n_workers, 1))) if n_todo else 1
    return max(1, min(wanted, balance))


def execute(runner, runs: list, store, *, workers=None, scheduler: str | None = None, client=None,
            chunk_size: int | None = None, progress=True, on_chunk=None,
            flush_interval_s: float = 0.0) -> ExecutionStats:
    """Run the `runs` not yet in `store`, writing each finished chunk to it.

    Parameters
    ----------
    runner : callable
        ``runner(params, seed) -> dict`` (:mod:`sweeps.runners`), already prepared.
    runs : list of RunSpec
    store : RunStore
    workers : int, optional
        Local cluster of this many worker processes (one thread each), started
        and stopped here; default one per core; ``0``: serial, in this process.
    scheduler : str, optional
        Address of a running Dask scheduler (``tcp://HOST:PORT``); its workers run the chunks.
    client : distributed.Client, optional
        An existing client (tests, notebooks); not closed here.
    chunk_size : int, optional
        Runs per task (default: see the module docstring).
    progress : file or bool
        Where the progress bar goes (``True``: stderr; ``None``/``False``: nowhere).
    on_chunk : callable, optional
        Called with each chunk's rows once they are recorded.
    flush_interval_s : float, s
        0 (default): each chunk is written the moment it arrives.  Above 0:
        rows are gathered and written at most once per interval (and at the
        end), for clusters so large that a file per chunk would be too many;
        a killed client then loses at most that interval's rows (``--resume`` reruns them).

    Returns
    -------
    ExecutionStats

    Raises
    ------
    MetricError
        A run's results lack a requested metric (the sweep stops: every run would).
    EngineError
        The cluster could not be started or the scheduler reached.
    """
    done = store.done()
    todo = [r for r in runs if r.run_id not in done]
    # nothing left to run (a finished sweep resumed): no cluster to start
    serial = (client is None and scheduler is None and workers == 0) or not todo
    setup_start = time.perf_counter()
    own_cluster = own_client = None
    if serial:
        n_workers, engine = 1, "serial"
    else:
        client, own_client, own_cluster, engine = _connect(client, scheduler, workers)
        n_workers = max(1, sum(client.nthreads().values()))
    setup_s = time.perf_counter() - setup_start
    size = _chunk_size(chunk_size, runner, len(todo), n_workers)
    chunks = chunked(todo, size)
    bar = ProgressBar(len(todo), stream=progress)
    writer = _Writer(store, flush_interval_s)
    busy = [0.0]
    failed = [0]

    def record(rows):
        writer.add(rows)
        n_bad = sum(r["status"] != "ok" for r in rows)
        failed[0] += n_bad
        busy[0] += sum(r["duration_s"] for r in rows)
        return n_bad

    start = time.perf_counter()
    try:
        if serial:
            for chunk in chunks:
                bar.update(running=len(chunk))
                rows = run_chunk(runner, chunk)
                bar.update(done=len(rows), failed=record(rows), running=0)
                if on_chunk is not None:
                    on_chunk(rows)
        elif chunks:
            _dask_loop(client, runner, chunks, n_workers, record, bar, on_chunk)
    finally:
        writer.flush()
        bar.close()
        if own_client is not None:
            own_client.close()
        if own_cluster is not None:
            own_cluster.close()
    return ExecutionStats(len(runs), len(runs) - len(todo), len(todo), failed[0], len(chunks), size, engine,
                          n_workers, time.perf_counter() - start, busy[0], setup_s)


class _Writer:
    """Rows to the store: at once, or gathered for `interval` s."""

    def __init__(self, store, interval: float):
        self.store, self.interval = store, float(interval)
        self.rows, self.last = [], time.perf_counter()

    def add(self, rows) -> None:
        self.rows.extend(rows)
        if self.interval <= 0 or time.perf_counter() - self.last >= self.interval:
            self.flush()

    def flush(self) -> None:
        if self.rows:
            self.store.write(self.rows)
            self.rows = []
        self.last = time.perf_counter()


def _connect(client, scheduler, workers):
    """(client, client to close, cluster to close, engine label)."""
    if client is not None:
        return client, None, None, f"client:{client.scheduler.address}"
    from distributed import Client, LocalCluster
    if scheduler is not None:
        try:
            own = Client(scheduler, timeout="20s")
        except (OSError, TimeoutError) as exc:
            raise EngineError(scheduler, f"cannot reach the Dask scheduler at {scheduler}: {exc}") from None
        return own, own, None, scheduler
    n = default_workers() if workers is None else int(workers)
    if n < 1:
        raise EngineError("", f"workers must be >= 0 (0: serial), got {workers!r}")
    try:
        cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None,
                               silence_logs=logging.ERROR)
    except Exception as exc:  # distributed raises several kinds; report one line
        raise EngineError("", f"cannot start a local Dask cluster of {n} workers: {exc}") from None
    own = Client(cluster)
    return own, own, cluster, f"local:{n}"


def _identity(x):
    return x


def _failed_rows(chunk, exc) -> list:
    text = f"{type(exc).__name__}: {exc}"[:4000]
    return [{"run_id": r.run_id, "status": "failed", "error": text, "seed": r.seed, "started": time.time(),
             "duration_s": 0.0,
             "worker": "", **{f"param.{k}": v for k, v in r.params.items()}} for r in chunk]


def _dask_loop(client, runner, chunks, n_workers, record, bar, on_chunk, *, retries: int = 2):
    """Run the chunks on the cluster, recording rows as chunks finish.  A run's own failure is a
    failed row from inside :func:`run_chunk`; a chunk whose future fails (its worker died, the
    task was lost) is infrastructure, so it is submitted again, up to `retries` times, before its
    runs are recorded as failed with the error."""
    from distributed import as_completed
    from distributed.client import FutureCancelledError
    shipped = client.submit(_identity, runner, pure=False, key=f"sweep-runner-{os.urandom(4).hex()}")

    def submit(chunk):
        return client.submit(run_chunk, shipped, chunk, pure=False,
                             key=f"sweep-chunk-{chunk[0].run_id}-{os.urandom(4).hex()}")

    futures = {submit(chunk): chunk for chunk in chunks}
    attempts = {chunk[0].run_id: 1 for chunk in chunks}
    size = len(chunks[0])
    pending = len(futures)
    bar.update(running=min(pending, n_workers) * size)
    try:
        queue = as_completed(list(futures))
        for future in queue:
            chunk = futures[future]
            try:
                rows = future.result()
                future.release()        # the rows are here now: no worker need keep (or recompute) them
            except MetricError:
                raise
            except (FutureCancelledError, Exception) as exc:  # KilledWorker and the like
                if attempts[chunk[0].run_id] <= retries:
                    attempts[chunk[0].run_id] += 1
                    again = submit(chunk)
                    futures[again] = chunk
                    queue.add(again)
                    continue
                rows = _failed_rows(chunk, exc)
            n_bad = record(rows)
            pending -= 1
            bar.update(done=len(rows), failed=n_bad, running=min(pending, n_workers) * size)
            if on_chunk is not None:
                on_chunk(rows)
    finally:
        client.cancel(list(futures) + [shipped])
