"""Simulate straight to a CSV file, segment by segment, for runs too long to hold in memory.

:func:`simulate_to_csv` cuts the span into segments of at most `chunk_samples`
output intervals on the same time grid as one run would use, simulates each
with :func:`bondgraph.numerics.simulation.simulate` from the previous segment's final
state and held values, and appends its rows to the file, so memory stays
bounded whatever the length.  Fixed-step models (held variables, ``RK4``)
give the same numbers as one run; adaptive solvers restart at each segment
boundary (differences within their tolerances).  Before anything runs, the
file's size is estimated and refused, naming the sizes, when the disk
cannot hold it.
"""
from __future__ import annotations

import csv
import math
import shutil
from pathlib import Path

import numpy as np

from ..errors import ArgumentError, OutputTooLargeError
from .progress import Progress
from .simulation import simulate
from ..system import StateEquations

__all__ = ["simulate_to_csv", "BYTES_PER_CSV_VALUE"]

#: Size of one value written with ``%.17g`` and its separator, bytes (an upper estimate).
BYTES_PER_CSV_VALUE = 25


def simulate_to_csv(system, t_span, path, *, output_interval: float, chunk_samples: int = 100_000,
                    progress: bool = False, **kwargs) -> dict:
    """Simulate `system` over `t_span`, writing the samples to `path` as they come.

    Parameters
    ----------
    system : StateEquations or object with ``equations()``
    t_span : (float, float)
        Start and end time, s.
    path : str or os.PathLike
        CSV file, in the format of :meth:`SimulationResult.to_csv`.
    output_interval : float, s
        Sample interval (required: it sets the file's size).
    chunk_samples : int
        Output intervals per segment (memory used is proportional to it).
    progress : bool
        One progress line on stderr for the whole run.
    **kwargs
        Passed to :func:`~bondgraph.numerics.simulation.simulate` (``inputs``, ``params``,
        ``x0``, ``method``, ``dt``, ``backend``...).

    Returns
    -------
    dict
        ``samples`` (rows written), ``segments``, ``path``.

    Raises
    ------
    ArgumentError
        A bad span, interval or `chunk_samples`, or a keyword that
        :func:`simulate` does not take (named).
    OutputTooLargeError
        The file would not fit on its disk (sizes in the message).
    """
    eqs = system if isinstance(system, StateEquations) else system.equations()
    try:
        t0, t1 = (float(v) for v in t_span)
    except (TypeError, ValueError):
        raise ArgumentError(f"t_span: expected (t0, t1) in seconds; found {t_span!r}", name="t_span") from None
    if not (math.isfinite(t0) and math.isfinite(t1) and t1 > t0):
        raise ArgumentError(f"t_span: expected finite t0 < t1; found ({t0}, {t1})", name="t_span")
    if not (isinstance(output_interval, (int, float)) and math.isfinite(output_interval) and output_interval > 0):
        raise ArgumentError(f"output_interval: expected a positive number of seconds; found {output_interval!r}",
                            name="output_interval")
    if not (isinstance(chunk_samples, int) and chunk_samples >= 1):
        raise ArgumentError(f"chunk_samples: expected a positive integer; found {chunk_samples!r}",
                            name="chunk_samples")
    if "held0" in kwargs:
        raise ArgumentError("held0 is set by the segments themselves; give x0 and the model's held_initial",
                            name="held0")
    n = int(math.floor((t1 - t0) / output_interval + 1e-9))
    samples = n + 1 + (1 if t1 - (t0 + n * output_interval) > 1e-9 * output_interval else 0)
    _check_disk(eqs, path, samples)
    bar = Progress(t1 - t0, fmt=f"simulate {eqs.name}: {{percentage:5.1f}} %  {{desc}}", enabled=progress,
                   start=t0, value_fmt="t = {:.6g} s")
    x0, held0, written, segments = kwargs.pop("x0", None), None, 0, 0
    try:
        with open(path, "w", newline="") as fh:
            for k in range(0, max(n, 1), chunk_samples):
                ta = t0 + k * output_interval
                tb = t1 if k + chunk_samples >= n else t0 + (k + chunk_samples) * output_interval
                result = simulate(eqs, (ta, tb), output_interval=output_interval, x0=x0, held0=held0,
                                  **kwargs)
                written += _append(fh, result, header=segments == 0, skip_first=segments > 0)
                segments += 1
                x0 = np.array([result[key][-1] for key in result.names_of("state")])
                held0 = np.array([result[key][-1] for key in result.names_of("held")])
                bar.update_to(tb)
    finally:
        bar.close()
    return {"samples": written, "segments": segments, "path": str(path)}


def _check_disk(eqs, path, samples: int) -> None:
    n_signals = 1 + len(eqs.states) + len(eqs.inputs) + len(eqs.outputs) + len(eqs.held) + len(eqs.algebraic)
    need = float(samples) * n_signals * BYTES_PER_CSV_VALUE
    folder = Path(path).resolve().parent
    try:
        free = shutil.disk_usage(folder).free
    except OSError:
        return   # a folder that does not exist fails at open(), naming the file
    if need > free:
        raise OutputTooLargeError(
            f"simulation of {eqs.name!r} to {str(path)!r}: {samples:.4g} samples of {n_signals} signals need about "
            f"{need / 2 ** 30:.3g} GiB of CSV, but {folder} has {free / 2 ** 30:.3g} GiB free",
            n_samples=min(samples, 2 ** 62), n_signals=n_signals, n_bytes=int(min(need, 2 ** 62)), available=free)


def _append(fh, result, *, header: bool, skip_first: bool) -> int:
    """Write `result`'s rows (and the header first) as :meth:`SimulationResult.to_csv` does."""
    if header:
        csv.writer(fh).writerow(["time [s]"] + [f"{n} [{result.units[n]}]" if result.units[n] else n
                                                for n in result.names])
    table = np.column_stack([result.t, *(result[n] for n in result.names)])
    if skip_first:   # the previous segment's last sample
        table = table[1:]
    np.savetxt(fh, table, fmt="%.17g", delimiter=",")
    return table.shape[0]
