"""A one-line progress bar for sweeps: done, failed, running, ETA."""
from __future__ import annotations

import sys
import time

__all__ = ["ProgressBar"]


class ProgressBar:
    """Prints ``[#####.....] 120/200 runs  3 failed  4 running  ETA 1m20s``.

    On a terminal the line is redrawn in place; otherwise a line is printed
    every 10 % of the runs (and at the end), so logs stay short.

    Parameters
    ----------
    total : int
        Runs to do in this session (not those resumed from disk).
    stream : file or bool, optional
        ``True`` (default): ``sys.stderr`` at the time of the call; ``None`` or ``False``: print nothing.
    """

    def __init__(self, total: int, *, stream=True, label: str = "runs"):
        if stream is True:
            stream = sys.stderr
        elif stream is False:
            stream = None
        self.total, self.stream, self.label = int(total), stream, label
        self.done = self.failed = self.running = 0
        self.start = time.perf_counter()
        self._tty = bool(stream is not None and getattr(stream, "isatty", lambda: False)())
        self._printed_decile = -1

    def eta_s(self) -> float | None:
        """Seconds left at the rate so far (None before the first run)."""
        if self.done == 0:
            return None
        rate = self.done / max(time.perf_counter() - self.start, 1e-9)
        return (self.total - self.done) / rate

    def line(self) -> str:
        """The current progress line."""
        width = 30
        filled = int(width * self.done / self.total) if self.total else width
        eta = self.eta_s()
        eta_text = "--" if eta is None else _duration(eta)
        return (f"[{'#' * filled}{'.' * (width - filled)}] {self.done}/{self.total} {self.label}  "
                f"{self.failed} failed  {self.running} running  elapsed "
                f"{_duration(time.perf_counter() - self.start)}  ETA {eta_text}")

    def update(self, *, done: int = 0, failed: int = 0, running: int | None = None) -> None:
        """Add `done` finished runs (of which `failed` failed); set the number `running`."""
        self.done += done
        self.failed += failed
        if running is not None:     # estimated by the caller from whole chunks: never more than are left
            self.running = max(0, min(int(running), self.total - self.done))
        if self.stream is None:
            return
        if self._tty:
            print("\r" + self.line(), end="", file=self.stream, flush=True)
            return
        decile = 10 * self.done // max(self.total, 1)
        if decile > self._printed_decile:
            self._printed_decile = decile
            print(self.line(), file=self.stream, flush=True)

    def close(self) -> None:
        """End the line."""
        if self.stream is not None and self._tty:
            print(file=self.stream, flush=True)


def _duration(seconds: float) -> str:
    seconds = int(round(seconds))
    if seconds < 60:
        return f"{seconds}s"
    if seconds < 3600:
        return f"{seconds // 60}m{seconds % 60:02d}s"
    return f"{seconds // 3600}h{seconds % 3600 // 60:02d}m"
