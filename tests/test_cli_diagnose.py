"""`bondcosim diagnose`: the command on a recording of the nominal model, and bad input
reported in one line naming the offending thing (exit status 1)."""
import json

import numpy as np
import pytest

from bondcosim.cli import main
from plants import library
from diagnosis.recording import Experiment
from diagnosis.residuals import simulate_outputs


@pytest.fixture(scope="module")
def nominal_csv(tmp_path_factory):
    """The library mass-spring-damper itself plus 2 mm of seeded noise, position in mm."""
    t = np.arange(0.0, 12.0, 0.02)
    force = 2.0 * np.sin(2 * np.pi * 0.4 * t)
    exp = Experiment(t, {"F": force}, {"x": t.copy()}, {"F": "N", "x": "m"})
    x = simulate_outputs(library.build("mass-spring-damper"), exp)["x"]
    x_mm = 1e3 * (x + np.random.default_rng(21).normal(0.0, 2e-3, t.size))
    path = tmp_path_factory.mktemp("cli") / "nominal.csv"
    path.write_text("t_ms,force,pos\n" + "".join(f"{1e3 * a:.3f},{f:.9g},{p:.6g}\n"
                                                 for a, f, p in zip(t, force, x_mm)))
    return str(path)


ARGS = ["--time", "t_ms:ms", "--input", "F=force:N", "--output", "x=pos:mm"]


def test_json_and_report(nominal_csv, tmp_path, capsys):
    out_dir = tmp_path / "report"
    assert main(["diagnose", "mass-spring-damper", nominal_csv, *ARGS, "--json",
                 "--report", str(out_dir)]) == 0
    captured = capsys.readouterr()
    data = json.loads(captured.out)
    assert data["missing_physics"][0]["kind"] == "none"
    assert data["fit"]["holdout"][1] == pytest.approx(11.98)      # ms converted to s
    assert data["improved_model"] == str(out_dir / "improved_model.json")
    assert (out_dir / "diagnosis.json").is_file() and (out_dir / "holdout_fit.png").is_file()
    assert "diagnose: [" in captured.err                            # progress lines


def test_text_output(nominal_csv, capsys):
    assert main(["diagnose", "mass-spring-damper", nominal_csv, *ARGS, "--holdout", "0.25"]) == 0
    out = capsys.readouterr().out
    # the last 25 % of 0-11.98 s: from the first sample at or after 8.985 s
    assert "Missing physics: none" in out and "held out 9-11.98 s." in out
    assert "Held-out NRMSE of x: nominal" in out


BAD = {
    "missing column": ("t,force,pos\n0,1,0\n1,1,1\n2,1,3\n", ["--output", "x=position"],
                       "no column 'position'"),
    "NaN gap": ("t,force,pos\n0,1,0\n1,1,\n2,1,3\n", ["--output", "x=pos"], "NaN gaps at data rows 1"),
    "time order": ("t,force,pos\n0,1,0\n2,1,1\n1,1,3\n", ["--output", "x=pos"],
                   "time column 't' does not increase"),
    "unknown unit": ("t,force,pos\n0,1,0\n1,1,1\n2,1,3\n", ["--output", "x=pos:parsec"],
                     "unknown symbol 'parsec'"),
    "constant output": ("t,force,pos\n0,1,2\n1,1,2\n2,1,2\n", ["--output", "x=pos"],
                        "column 'pos' bound to output 'x' is constant"),
    "unknown output": ("t,force,pos\n0,1,0\n1,1,1\n2,1,3\n", ["--output", "y=pos"],
                       "unknown output 'y'"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_input_one_line(case, tmp_path, capsys):
    text, extra, words = BAD[case]
    path = tmp_path / "bad.csv"
    path.write_text(text)
    assert main(["diagnose", "mass-spring-damper", str(path), "--input", "F=force", *extra]) == 1
    errors = [line for line in capsys.readouterr().err.splitlines() if "error" in line]
    assert len(errors) == 1 and errors[0].startswith("bondcosim diagnose: error:")
    assert words in errors[0]


def test_unknown_model(nominal_csv, capsys):
    assert main(["diagnose", "no-such-model", nominal_csv, *ARGS]) == 1
    assert "unknown model 'no-such-model'" in capsys.readouterr().err


def test_a_glitch_is_named_and_replaced_unless_kept(nominal_csv, tmp_path, capsys):
    """One sample of the position 80 noise standard deviations off (a sensor glitch): the report
    names it and the null recording still reads none; --keep-spikes uses it as recorded."""
    lines = open(nominal_csv).read().splitlines()
    row = lines[301].split(",")
    row[2] = f"{float(row[2]) + 160.0:.6g}"                        # mm; the noise is 2 mm
    lines[301] = ",".join(row)
    path = tmp_path / "glitch.csv"
    path.write_text("\n".join(lines) + "\n")
    assert main(["diagnose", "mass-spring-damper", str(path), *ARGS]) == 0
    out = capsys.readouterr().out
    assert "Note: output x: 1 isolated spike(s) at t = 6 s" in out and "Missing physics: none" in out
    assert main(["diagnose", "mass-spring-damper", str(path), *ARGS, "--keep-spikes"]) == 0
    assert "isolated spike" not in capsys.readouterr().out
