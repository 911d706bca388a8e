"""Refuse results that would not fit in memory, before any work is done.

A simulation asked for ``--stop-time 1e9 --output-interval 1e-6`` needs 10^15
samples; numpy would fail deep inside with "Unable to allocate 7.11 PiB".
:func:`check_result_size` says so first, naming the sizes.
"""
from __future__ import annotations

import math
import os

from ..errors import OutputTooLargeError

__all__ = ["available_memory", "check_result_size", "BYTES_PER_VALUE", "COPIES"]

#: float64.
BYTES_PER_VALUE = 8
#: Arrays of the result's size alive at once (integration buffers, the result, its CSV rows).
COPIES = 3


def available_memory() -> int:
    """Memory available to this process, bytes (``MemAvailable`` on Linux; else
    free physical pages; 4 GiB when neither is known)."""
    try:
        with open("/proc/meminfo", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return int(os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):
        return 4 << 30


def _size(n: float) -> str:
    for unit, scale in (("PiB", 2 ** 50), ("TiB", 2 ** 40), ("GiB", 2 ** 30), ("MiB", 2 ** 20), ("KiB", 2 ** 10)):
        if n >= scale:
            return f"{n / scale:.3g} {unit}"
    return f"{n:.0f} B"


def check_result_size(span: float, interval: float, n_signals: int, *, what: str = "simulation",
                      available: int | None = None) -> int:
    """Number of samples of a result sampled every `interval` s over `span` s,
    after checking that it fits in memory.

    Parameters
    ----------
    span, interval : float, s
        Length of the run and sample interval (both > 0).
    n_signals : int
        Values per sample (time, states, inputs, outputs, held variables).
    what : str
        Named in the message.
    available : int, optional
        Bytes available (default :func:`available_memory`).

    Raises
    ------
    OutputTooLargeError
        The result needs more than half the available memory; the message
        gives samples, signals, bytes and what is available.
    """
    samples = math.floor(span / interval + 1e-9) + 2
    need = float(samples) * n_signals * BYTES_PER_VALUE * COPIES
    have = available_memory() if available is None else int(available)
    if need > have / 2:
        raise OutputTooLargeError(
            f"{what}: {samples:.4g} samples ({span:g} s every {interval:g} s) of {n_signals} signals need about "
            f"{_size(need)} in memory, {have and need / have:.3g} times the {_size(have)} available; "
            "use a longer output interval or a shorter span",
            n_samples=min(samples, 2 ** 62), n_signals=n_signals, n_bytes=int(min(need, 2 ** 62)), available=have)
    return samples
