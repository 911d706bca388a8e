"""The sweep progress line: done, failed, running, ETA.

On a terminal the line is the project's one progress helper,
:class:`bondgraph.numerics.progress.Progress` (tqdm), redrawn in place; in a
log (not a terminal) one line is printed per 10 % of the runs, so logs stay
short and a finished sweep's log says how it went.
"""
from __future__ import annotations

import sys
import time

from bondgraph.numerics.progress import Progress

__all__ = ["ProgressBar"]

_TQDM_FORMAT = "[{bar:30}] {n:.0f}/{total:.0f} {unit}  {desc}  elapsed {elapsed}  ETA {remaining}"


class ProgressBar:
    """Counts runs and shows ``[#####.....] 120/200 runs  3 failed  4 running  elapsed 2m05s  ETA 1m20s``.

    Parameters
    ----------
    total : int
        Runs to do in this session (not those resumed from disk).
    stream : file or bool, optional
        ``True`` (default): ``sys.stderr`` at the time of the call; ``None`` or ``False``: print nothing.
    label : str, optional
        What is counted ("runs", "recordings").
    """

    def __init__(self, total: int, *, stream=True, label: str = "runs"):
        if stream is True:
            stream = sys.stderr
        elif stream is False:
            stream = None
        self.total, self.stream, self.label = int(total), stream, label
        self.done = self.failed = self.running = 0
        self.start = time.perf_counter()
        tty = bool(stream is not None and getattr(stream, "isatty", lambda: False)())
        self._bar = (Progress(self.total, fmt=_TQDM_FORMAT.replace("{unit}", label), file=stream)
                     if tty else None)
        self._printed_decile = -1

    def eta_s(self) -> float | None:
        """Seconds left at the rate so far (None before the first run)."""
        if self.done == 0:
            return None
        rate = self.done / max(time.perf_counter() - self.start, 1e-9)
        return (self.total - self.done) / rate

    def counts(self) -> str:
        """``3 failed  4 running``."""
        return f"{self.failed} failed  {self.running} running"

    def line(self) -> str:
        """The current progress line, as a log shows it."""
        width = 30
        filled = int(width * self.done / self.total) if self.total else width
        eta = self.eta_s()
        eta_text = "--" if eta is None else _duration(eta)
        return (f"[{'#' * filled}{'.' * (width - filled)}] {self.done}/{self.total} {self.label}  "
                f"{self.counts()}  elapsed {_duration(time.perf_counter() - self.start)}  ETA {eta_text}")

    def update(self, *, done: int = 0, failed: int = 0, running: int | None = None) -> None:
        """Add `done` finished runs (of which `failed` failed); set the number `running`."""
        self.done += done
        self.failed += failed
        if running is not None:     # estimated by the caller from whole chunks: never more than are left
            self.running = max(0, min(int(running), self.total - self.done))
        if self._bar is not None:
            self._bar.update_to(self.done, note=self.counts())
            return
        if self.stream is None:
            return
        decile = 10 * self.done // max(self.total, 1)
        if decile > self._printed_decile:
            self._printed_decile = decile
            print(self.line(), file=self.stream, flush=True)

    def close(self) -> None:
        """End the line."""
        if self._bar is not None:
            self._bar.close(self.done, note=self.counts())
            self._bar = None


def _duration(seconds: float) -> str:
    seconds = int(round(seconds))
    if seconds < 60:
        return f"{seconds}s"
    if seconds < 3600:
        return f"{seconds // 60}m{seconds % 60:02d}s"
    return f"{seconds // 3600}h{seconds % 3600 // 60:02d}m"
