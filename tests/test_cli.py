"""The console script, called in-process through main([...])."""
import json

import numpy as np
import pytest

from bondcosim.cli import main


def test_list_names_every_builtin_model(capsys):
    from plants import library
    assert main(["list"]) == 0
    out = capsys.readouterr().out
    for name in library.names():
        assert name in out


def test_equations_text(capsys):
    assert main(["equations", "mass-spring-damper"]) == 0
    out = capsys.readouterr().out   # assignments first, then the state equations over them
    assert "f_m     = p_m/m" in out and "dp_m/dt = F - b*f_m - k*q_k" in out
    assert main(["equations", "mass-spring-damper", "--flat"]) == 0
    out = capsys.readouterr().out
    assert "dp_m/dt" in out and "F - b*p_m/m - k*q_k" in out and "f_m     =" not in out


def test_equations_json_has_the_documented_keys_and_matrices(capsys):
    assert main(["equations", "mass-spring-damper", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert set(data) == {"states", "inputs", "outputs", "parameters", "f", "h", "assignments", "f_short",
                         "h_short", "A", "B", "C", "D", "linearisation"}
    m, b, k = 1.0, 0.4, 4.0   # library defaults
    assert data["states"] == ["p_m", "q_k"] and data["parameters"] == {"m": m, "b": b, "k": k}
    assert np.allclose(data["A"], [[-b / m, -k], [1 / m, 0.0]])
    assert np.allclose(data["B"], [[1.0], [0.0]])
    assert np.allclose(data["C"], [[0.0, 1.0], [1 / m, 0.0]])


def test_equations_latex(capsys):
    assert main(["equations", "rlc", "--latex"]) == 0
    assert capsys.readouterr().out.startswith("\\begin{aligned}")


def test_equations_of_a_python_model_file(tmp_path, capsys):
    path = tmp_path / "my_model.py"
    path.write_text(
        "from bondgraph import BondGraph, Se, I, R, One\n"
        "def build():\n"
        "    g = BondGraph('damped')\n"
        "    for e in (Se('F'), One('j'), I('m', 2.0), R('b', 0.5)):\n"
        "        g.add(e)\n"
        "    g.connect('F', 'j'); g.connect('j', 'm'); g.connect('j', 'b')\n"
        "    return g\n")
    assert main(["equations", str(path), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["f"] == ["F - b*p_m/m"] and data["A"] == [[-0.25]]


def test_equations_of_a_json_model_file(tmp_path, capsys):
    from bondgraph.io_json import save
    from plants import library
    path = tmp_path / "rlc.json"
    save(library.build("rlc"), path)
    assert main(["equations", str(path), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["states"] == ["p_L", "q_Cs"]


def test_draw_writes_a_png(tmp_path):
    out = tmp_path / "motor.png"
    assert main(["draw", "dc-motor", "-o", str(out)]) == 0
    assert out.stat().st_size > 5000 and out.read_bytes()[:4] == b"\x89PNG"


def test_simulate_writes_csv_with_inputs_and_parameters(tmp_path):
    from bondgraph.numerics.results import SimulationResult
    csv, png = tmp_path / "rlc.csv", tmp_path / "rlc.png"
    code = main(["simulate", "rlc", "--stop-time", "0.5", "--input", "V=2", "--param", "Rs=20",
                 "--output-interval", "0.01", "-o", str(csv), "--plot", str(png)])
    assert code == 0 and png.exists()
    res = SimulationResult.from_csv(csv)
    assert res.t[-1] == pytest.approx(0.5)
    assert res["v_C"][-1] == pytest.approx(2.0, abs=1e-3)   # the capacitor charges to the source voltage


@pytest.mark.parametrize("argv, needle", [
    (["equations", "no-such-model"], "no-such-model"),
    (["equations", "missing.json"], "missing.json"),
    (["simulate", "rlc", "--stop-time", "1", "--input", "V=sin(t", "-o", "x.csv"], "sin(t"),
    (["simulate", "rlc", "--stop-time", "1", "--input", "Vx=1", "-o", "x.csv"], "Vx"),
    (["simulate", "rlc", "--stop-time", "1", "--param", "Rs=ten", "-o", "x.csv"], "Rs"),
    (["simulate", "rlc", "--stop-time", "1", "--input", "V", "-o", "x.csv"], "NAME=VALUE"),
])
def test_bad_input_is_one_clear_line(argv, needle, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert needle in err and "Traceback" not in err


def test_version(capsys):
    with pytest.raises(SystemExit) as info:
        main(["--version"])
    assert info.value.code == 0 and "bondcosim" in capsys.readouterr().out


def test_compare_exoskeleton_json(capsys, tmp_path):
    assert main(["compare", "exoskeleton", "--json", "--plot", str(tmp_path)]) == 0
    data = json.loads(capsys.readouterr().out)
    assert set(data) == {"max_abs_error", "rms_error", "matrices_equal"}
    assert data["matrices_equal"] is True
    # same linear model on both sides: agreement to solver tolerance (Sec. 5.1 run)
    assert data["max_abs_error"]["tau_s"] < 1e-6 and data["max_abs_error"]["w_m"] < 1e-6
    assert (tmp_path / "exoskeleton_section_5_1.png").stat().st_size > 10000


def test_compare_pam_json(capsys):
    assert main(["compare", "pam", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["matrices_equal"] is None          # nonlinear model
    assert set(data["max_abs_error"]) == {"psi", "P1", "P2", "tau"}
    assert data["max_abs_error"]["P1"] < 1e-3      # Pa, on pressures of a few hundred kPa
