"""``bondcosim export-fmu`` and ``bondcosim fmu-info``."""
from __future__ import annotations

import json

from fmpy.validation import validate_fmu

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
