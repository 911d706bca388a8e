"""End to end: :func:`diagnosis.diagnose` on the test set of concealed effects (issue 6, "Prove it").

For each case of ``tests/data/diagnosis/cases.json`` (written by ``python -m diagnosis.cases``):
the kind found is the concealed one, attached at the concealed place (or at a place no
recording can tell apart from it, listed in the manifest's ``equivalent_places``), and the
held-out NRMSE of the affected output drops by at least 50 %; a null case answers ``none``.

A diagnosis takes 0.2 s to 2 min on this 2-core machine (all 14 cases: 6.5 min), so by
default only the ``QUICK`` cases run (about 45 s: five kinds, three at junctions, one at an input and one at an
output on four models, and the null cases of pam, the exoskeleton and the mass-spring-damper),
and the command line on a null case.  ``BONDCOSIM_DIAGNOSIS_CASES=all`` (or a comma-separated
list of names) runs the others too.  Cases the tool does not get right yet are strict xfails carrying the reason
measured, never skipped silently.
"""
from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from diagnosis.diagnose import diagnose

DATA = Path(__file__).parent / "data" / "diagnosis"
CASES = {e["name"]: e for e in json.loads((DATA / "cases.json").read_text())["cases"]}
QUICK = ("msd_coulomb", "msd_hardening", "dcmotor_saturation", "rlc_sensor_gain", "tanks_leak",
         "msd_null", "pam_null", "exo_null")
_CHOSEN = os.environ.get("BONDCOSIM_DIAGNOSIS_CASES", "")
SELECTED = set(CASES) if _CHOSEN == "all" else set(QUICK) | {n for n in _CHOSEN.split(",") if n}

#: cases the tool does not get right yet: name -> the reason measured (strict xfail, so a case
#: that starts passing fails here until it is removed).  Measured on main at c56405e with
#: BONDCOSIM_DIAGNOSIS_CASES=all: all 14 cases pass (4 min 34 s on 2 shared cores); again at
#: 9958529 with two diagnosis rounds: all pass, 6 min 29 s on a quiet 2-core machine.  At 447272b,
#: before graph location handled actuator places and held friction laws, dcmotor_saturation and
#: exo_delay answered 'none' and the three pam cases failed in graph location.
KNOWN_FAILURES: dict[str, str] = {}


def _params():
    unknown = SELECTED - set(CASES)
    if unknown:
        raise ValueError(f"BONDCOSIM_DIAGNOSIS_CASES names no case {sorted(unknown)}; cases are "
                         f"{', '.join(CASES)} (or 'all')")
    out = []
    for name in CASES:
        marks = []
        if name not in SELECTED:
            marks.append(pytest.mark.skip(reason="long diagnosis: BONDCOSIM_DIAGNOSIS_CASES=all runs it"))
        elif name in KNOWN_FAILURES:
            marks.append(pytest.mark.xfail(reason=KNOWN_FAILURES[name], strict=True))
        out.append(pytest.param(name, marks=marks))
    return out


@pytest.mark.parametrize("name", _params())
def test_diagnosis_names_locates_and_improves(name):
    e = CASES[name]
    report = diagnose(e["model"], str(DATA / e["file"]), inputs=e["inputs"], outputs=e["outputs"],
                      time=e["time"])
    result = report.to_json()
    found = result["missing_physics"][0]
    if e["kind"] == "none":
        assert found["kind"] == "none", found
        return
    places = [e["place"]] + e["equivalent_places"]
    assert found["kind"] == e["kind"], found
    assert found["attached_to"] in [f"{p['kind']} {p['name']}" for p in places], found
    out = e["affected_output"]
    nominal, improved = result["fit"]["nominal"][out], result["fit"]["improved"][out]
    assert improved <= 0.5 * nominal, (out, nominal, improved)


def test_command_line_on_a_null_case(capsys):
    """``bondcosim diagnose ... --json`` with the manifest's bindings (mN m, deg/s, rpm columns)."""
    from bondcosim.cli import main
    e = CASES["exo_null"]
    argv = ["diagnose", e["model"], str(DATA / e["file"]), "--time", e["time"], "--json"]
    for b in e["inputs"]:
        argv += ["--input", b]
    for b in e["outputs"]:
        argv += ["--output", b]
    assert main(argv) == 0
    result = json.loads(capsys.readouterr().out)
    assert [m["kind"] for m in result["missing_physics"]] == ["none"]
    assert set(result["fit"]["nominal"]) == {"tau_s", "w_m"}
    assert result["fit"]["improved"] == result["fit"]["nominal"]
