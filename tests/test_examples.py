"""Every example runs (as a user would run it) and its numbers make physical sense."""
from pathlib import Path

import pytest

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def test_quickstart(tmp_path, load_script):
    result = load_script("examples/quickstart.py").main(tmp_path)
    assert result["x"][-1] == pytest.approx(1.0 / 4.0, abs=0.01)   # static deflection F/k
    for name in ("quickstart.csv", "quickstart.png", "quickstart_graph.png", "quickstart_graph.json"):
        assert (tmp_path / name).stat().st_size > 0


def test_pneumatic_cylinder(tmp_path, load_script):
    result = load_script("examples/pneumatic_cylinder.py").main(tmp_path)
    # equilibrium: (P - Pa) Ap = k (x - x0) with P -> Ps (the valve stops only when P = Ps)
    Ps, Pa, Ap, k, x0 = 6e5, 1.013e5, 4.9e-4, 2000.0, 0.01
    assert result["P_kPa"][-1] == pytest.approx(Ps / 1000, rel=1e-3)
    assert result["stroke"][-1] == pytest.approx(x0 + (Ps - Pa) * Ap / k, rel=0.01)
    assert (tmp_path / "pneumatic_cylinder.png").exists()


def test_examples_are_all_tested():
    tested = {"quickstart", "pneumatic_cylinder"}
    assert {p.stem for p in EXAMPLES.glob("*.py")} == tested
