"""Progress lines of long runs (simulation, co-simulation, batch filtering) on tqdm.

One helper for every layer, so every long command shows its progress the
same way: a self-overwriting line on stderr, refreshed at most every 0.2 s,
finished with a newline.  tqdm is imported only when a line is shown (cheap
imports for the CLI).

Examples
--------
>>> bar = Progress(10.0, fmt="simulate msd: {percentage:5.1f} %  {desc}", enabled=False,
...                value_fmt="t = {:.6g} s")
>>> bar.update_to(5.0); bar.close()
"""
from __future__ import annotations

import sys
import time

__all__ = ["Progress"]


class Progress:
    """A progress line on stderr, or nothing when not `enabled`.

    Parameters
    ----------
    total : float
        Amount of work (samples, seconds of simulated time).
    fmt : str
        tqdm ``bar_format``: ``{percentage}``, ``{n}``, ``{total}``, ``{bar}``,
        ``{desc}`` (`value_fmt` of the value given to :meth:`update_to`), ``{elapsed}``...
    enabled : bool
        Show the line.
    start : float
        Value at which no work is done (``t0`` of a simulation).
    value_fmt : str, optional
        Format of ``{desc}`` from the current value, e.g. ``"t = {:.6g} s"``.
    file : file object, optional
        Where to write (default ``sys.stderr``).
    """

    def __init__(self, total: float, *, fmt: str, enabled: bool = True, start: float = 0.0,
                 value_fmt: str = "", file=None):
        self._bar, self.start, self.value_fmt, self._last = None, float(start), value_fmt, -1.0
        if enabled:
            from tqdm import tqdm
            self._bar = tqdm(total=total, bar_format=fmt, file=file or sys.stderr, mininterval=0.2,
                             ascii=".#", leave=True, dynamic_ncols=False)

    def update_to(self, value: float, *, note: str | None = None) -> None:
        """Set the current value (work done = value - start); redrawn at most every 0.2 s.
        Cheap when disabled or called often (once per right-hand-side evaluation).
        `note`, if given, is shown as ``{desc}`` instead of `value_fmt` (e.g. ``3 failed``)."""
        if self._bar is None:
            return
        now = time.monotonic()
        if now - self._last < 0.2:
            return
        self._last = now
        self._describe(value, note)
        self._bar.update(value - self.start - self._bar.n)

    def close(self, value: float | None = None, *, note: str | None = None) -> None:
        """Show the finished line (at `value`, default the end) and end it with a newline."""
        if self._bar is None:
            return
        end = self.start + self._bar.total if value is None else value
        self._describe(end, note)
        self._bar.n = end - self.start
        self._bar.refresh()
        self._bar.close()
        self._bar = None

    def _describe(self, value: float, note: str | None) -> None:
        if note is not None:
            self._bar.set_description_str(note, refresh=False)
        elif self.value_fmt:
            self._bar.set_description_str(self.value_fmt.format(value), refresh=False)
