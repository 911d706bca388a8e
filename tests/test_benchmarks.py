"""Each benchmark runs once at its smallest size (no timing asserted), so none can rot."""
import importlib.util
from pathlib import Path

BENCH = Path(__file__).resolve().parent.parent / "benchmarks"


def _load(name):
    spec = importlib.util.spec_from_file_location(f"bench_{name}", BENCH / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_derivation_benchmark_runs(capsys):
    bench = _load("derivation")
    bench.main(sizes=(2,), skip_bgt=True, repeats=1)
    out = capsys.readouterr().out
    assert "states" in out and "    2 " in out
