"""``bondcosim export-fmu`` and ``bondcosim fmu-info``."""
from __future__ import annotations

import json
import math

import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.validation import validate_fmu

import plants.library as library
from bondcosim.cli import main


def test_export_fmu_writes_a_valid_fmu_and_fmu_info_lists_it(tmp_path, capsys):
    path = tmp_path / "pam.fmu"
    assert main(["export-fmu", "pam-locked", "-o", str(path), "--fmi", "2",
                 "--param", "P_tank=6e5"]) == 0
    assert "CoSimulation" in capsys.readouterr().out
    assert validate_fmu(str(path)) == []
    assert main(["fmu-info", str(path), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["fmi_version"] == "2.0" and info["interfaces"] == ["ModelExchange", "CoSimulation"]
    by_name = {v["name"]: v for v in info["variables"]}
    assert by_name["u1"]["causality"] == "input" and by_name["u1"]["unit"] == "V"
    assert by_name["tau"]["causality"] == "output" and by_name["tau"]["start"] is None
    assert by_name["P_tank"]["causality"] == "parameter" and float(by_name["P_tank"]["start"]) == 6e5
    assert [v["causality"] for v in info["variables"]][:2] == ["input", "input"]
    assert main(["fmu-info", str(path)]) == 0
    table = capsys.readouterr().out
    assert "pam" in table.splitlines()[0] and "FMI 2.0" in table
    assert any(line.split()[:4] == ["tau", "output", "continuous", "N"] for line in table.splitlines())


def test_fmu_cli_errors_are_one_line_naming_the_culprit(tmp_path, capsys):
    assert main(["fmu-info", str(tmp_path / "missing.fmu")]) == 1
    err = capsys.readouterr().err
    assert "missing.fmu" in err and err.count("\n") == 1
    bad = tmp_path / "bad.fmu"
    bad.write_bytes(b"not a zip")
    assert main(["fmu-info", str(bad)]) == 1
    assert "bad.fmu" in capsys.readouterr().err
    assert main(["export-fmu", "rlc", "-o", str(tmp_path / "x.fmu"), "--param", "R_nope=1"]) == 1
    assert "R_nope" in capsys.readouterr().err


def test_export_fmu_options_reach_the_model_description(tmp_path, capsys):
    path = tmp_path / "msd.fmu"
    assert main(["export-fmu", "mass-spring-damper", "-o", str(path), "--fmi", "3", "--solver", "dopri",
                 "--tolerance", "1e-9", "--max-substeps", "100", "--solver-step", "2e-3",
                 "--stop-time", "10", "--step-size", "1", "--identifier", "msd_dp", "--author", "ACME",
                 "--fmu-version", "2.1", "--license", "BSD-3-Clause", "--copyright", "(c) ACME",
                 "--description", "a damped mass"]) == 0
    assert "wrote" in capsys.readouterr().out
    assert validate_fmu(str(path)) == []
    md = read_model_description(str(path))
    start = {v.name: v.start for v in md.modelVariables}
    assert (float(start["solver"]), float(start["tolerance"]), float(start["max_substeps"]),
            float(start["solver_step"])) == (1.0, 1e-9, 100.0, 2e-3)
    assert (md.defaultExperiment.stopTime, md.defaultExperiment.stepSize) == ("10.0", "1.0")
    assert (md.coSimulation.modelIdentifier, md.author, md.version, md.license, md.copyright,
            md.description) == ("msd_dp", "ACME", "2.1", "BSD-3-Clause", "(c) ACME", "a damped mass")
    # 1 s communication steps within 100 sub-steps: only the variable-step solver manages
    # (fixed RK4 at 2 ms would need 500, test_fmu_variable_step); analytic step response of
    # m x'' + b x' + k x = F from rest at t = 10 s, as there
    res = simulate_fmu(str(path), stop_time=10.0, output_interval=1.0, start_values={"F": 2.0},
                       output=["q_k"])
    p = library.build("mass-spring-damper").equations().param_values
    wn, zeta = math.sqrt(p["k"] / p["m"]), p["b"] / (2 * math.sqrt(p["k"] * p["m"]))
    wd = wn * math.sqrt(1 - zeta ** 2)
    x = 2.0 / p["k"] * (1 - math.exp(-zeta * wn * 10) * (math.cos(wd * 10)
                                                        + zeta * wn / wd * math.sin(wd * 10)))
    assert res["q_k"][-1] == pytest.approx(x, abs=1e-8)


@pytest.mark.parametrize("argv, status, text", [
    (["--solver", "euler"], 2, "invalid choice: 'euler'"),
    (["--tolerance", "abc"], 2, "invalid float value: 'abc'"),
    (["--tolerance", "-1"], 1, "tolerance must be a positive number, got -1.0"),
    (["--max-substeps", "0"], 1, "max_substeps must be a finite number >= 1, got 0.0"),
    (["--solver-step", "0"], 1, "solver_step must be a positive number of seconds"),
    (["--stop-time", "-2"], 1, "stop_time must be a positive number of seconds, got -2.0"),
    (["--identifier", "../evil"], 1, "identifier must be a C identifier"),
    (["--fmi", "4"], 2, "invalid choice: 4"),
])
def test_export_fmu_bad_options_are_one_line(tmp_path, capsys, argv, status, text):
    out = tmp_path / "x.fmu"
    try:
        code = main(["export-fmu", "rlc", "-o", str(out), *argv])
    except SystemExit as exc:   # argparse usage errors
        code = exc.code
    err = capsys.readouterr().err
    assert code == status and text in err and err.count("\n") == 1, err
    assert not out.exists()


def test_export_fmu_dopri_refused_for_held_variables(tmp_path, capsys):
    assert main(["export-fmu", "pam", "-o", str(tmp_path / "p.fmu"), "--solver", "dopri"]) == 1
    err = capsys.readouterr().err
    assert "solver 'dopri' is not offered by 'pam'" in err and "rk4" in err
