"""How many threads the compiled sample loops may use.

The C sample loops (:mod:`bondgraph.numerics.evaluate_samples_c`) release the GIL, so the
rows of a batch, or several runs (the diagnosis's location, :mod:`diagnosis.graph_location`),
can be integrated by several threads at once.  By default as many threads as
this process may run on cores.  ``BONDCOSIM_THREADS=1`` turns it off for a process, and
:func:`limited` for a block of code (a sweep's worker, which already has a core of its own).
"""
from __future__ import annotations

import os
from contextlib import contextmanager

from ..errors import ArgumentError

__all__ = ["worker_threads", "limited"]

_LIMITS: list = []


@contextmanager
def limited(threads: int):
    """Within the block, :func:`worker_threads` is at most `threads`."""
    _LIMITS.append(max(1, int(threads)))
    try:
        yield
    finally:
        _LIMITS.pop()


def worker_threads() -> int:
    """``$BONDCOSIM_THREADS`` if set (at least 1), else the cores this process may run on; at
    most the innermost :func:`limited`."""
    if _LIMITS:
        return min(_LIMITS[-1], _environment_threads())
    return _environment_threads()


def _environment_threads() -> int:
    text = os.environ.get("BONDCOSIM_THREADS", "").strip()
    if text:
        try:
            return max(1, int(text))
        except ValueError:
            raise ArgumentError(f"BONDCOSIM_THREADS must be a whole number; found {text!r}") from None
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:              # not on Linux
        return max(1, os.cpu_count() or 1)
