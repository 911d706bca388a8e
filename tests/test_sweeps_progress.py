"""The sweep progress line: done, failed, running, ETA."""
import io

from sweeps.progress import ProgressBar


def test_progress_line_counts_and_prints_once_per_decile():
    stream = io.StringIO()
    bar = ProgressBar(20, stream=stream)
    bar.update(running=4)
    assert "0/20 runs  0 failed  4 running" in bar.line() and bar.line().endswith("ETA --")
    for _ in range(18):
        bar.update(done=1, failed=1 if bar.done % 5 == 0 else 0, running=4)
    assert "18/20 runs  4 failed  2 running" in bar.line()      # whole chunks estimated: capped at what is left
    for _ in range(2):
        bar.update(done=1, running=4)
    line = bar.line()
    assert "[" + "#" * 30 + "] 20/20 runs  4 failed  0 running" in line and line.endswith("ETA 0s")
    # not a terminal: one line per 10 % (and the first), not one per update
    assert len(stream.getvalue().splitlines()) == 11


def test_progress_can_be_silent():
    bar = ProgressBar(3, stream=None)
    bar.update(done=3)
    bar.close()
    assert bar.done == 3 and bar.eta_s() == 0.0


class _Terminal(io.StringIO):
    def isatty(self):
        return True


def test_on_a_terminal_the_line_is_the_projects_tqdm_progress():
    stream = _Terminal()
    bar = ProgressBar(4, stream=stream, label="recordings")
    bar.update(done=3, failed=1, running=1)
    bar.close()
    last = stream.getvalue().replace("\r", "\n").strip().splitlines()[-1]
    assert last.startswith("[" + "#" * 22) and "3/4 recordings  1 failed  1 running" in last
    assert "ETA" in last and stream.getvalue().endswith("\n")
