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


def test_readable_equations(tmp_path, load_script, capsys):
    result = load_script("examples/readable_equations.py").main(tmp_path)
    assert {"valve1.alpha", "muscle1.V", "muscle1.F", "f_valve1"} <= set(result["names"])
    assert max(result["short"]) < 120 < 2000 < min(result["flat"][:2]) and result["round_trip"]
    assert "valve1.alpha" in capsys.readouterr().out and (tmp_path / "pam_equations.tex").stat().st_size > 0


def test_linearise_switched(tmp_path, load_script):
    result = load_script("examples/linearise_switched.py").main(tmp_path)
    assert result["rest"].derivatives["u1"].startswith("one-sided")
    assert set(result["working"].derivatives.values()) == {"symbolic"}
    # the valve opens: more voltage, more pressure rise in its own muscle only
    assert result["working"].B[0, 0] > 0 and result["working"].B[0, 1] == 0
    assert (tmp_path / "pam_linear.json").exists()


def test_results_to_pandas(tmp_path, load_script):
    pytest.importorskip("pandas")
    pytest.importorskip("xarray")
    result = load_script("examples/results_to_pandas.py").main(tmp_path)
    frame, data = result["frame"], result["dataset"]
    assert frame.attrs["units"]["w_m"] == "rad/s" and data["w_m"].attrs["units"] == "rad/s"
    assert data["t"].attrs["units"] == "s" and frame.index.name == "t"
    # same numbers both ways; steady speed of the motor: w = km V / (Ra bm + km^2) / n ... both equal
    assert frame["w_m"].to_numpy() == pytest.approx(data["w_m"].to_numpy())
    assert (tmp_path / "dc_motor_pandas.csv").exists()


def test_errors(load_script):
    messages = load_script("examples/errors.py").main()
    assert messages["negative span"][:2] == ("ArgumentError", "ValueError")
    assert messages["unknown input"][:2] == ("UnknownNameError", "ValueError") and "'Q'" in messages["unknown input"][2]
    assert messages["too many samples"][:2] == ("OutputTooLargeError", "MemoryError")


def test_notebook_display(tmp_path, load_script):
    result = load_script("examples/notebook_display.py").main(tmp_path)
    assert result["svg"].lstrip().startswith("<?xml") and "<svg" in result["svg"]
    assert result["latex"].startswith("$\\begin{aligned}")
    assert result["control"].nstates == 2


def test_examples_are_all_tested():
    tested = {"quickstart", "pneumatic_cylinder", "readable_equations", "linearise_switched", "results_to_pandas",
              "errors", "notebook_display"}
    assert {p.stem for p in EXAMPLES.glob("*.py")} == tested
