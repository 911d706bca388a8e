"""Every subcommand fails cleanly: one line on stderr naming the culprit, a documented exit
status, never a traceback (bondcosim/cli.py); a closed pipe is quiet."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from bondcosim.cli import main

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture
def files(tmp_path):
    rec = tmp_path / "rec.csv"
    rec.write_text("t,force,pos\n0,1,0\n0.1,1,0.01\n0.2,1,0.02\n0.3,1,0.03\n")
    bad = tmp_path / "bad.fmu"
    bad.write_bytes(b"not a zip")
    taken = tmp_path / "taken"
    taken.write_text("a file where a directory is wanted")
    return {"rec": str(rec), "bad": str(bad), "taken": str(taken), "out": str(tmp_path / "o.csv"),
            "missing": str(tmp_path / "missing.json"), "png": str(tmp_path / "g.png"),
            "fmu": str(tmp_path / "x.fmu"), "nodir": str(tmp_path / "no" / "such" / "o.csv"),
            "dir": str(tmp_path / "sweep-out"), "nomatch": str(tmp_path / "none*.csv")}


# (argv with {placeholders}, exit status, text the one-line message must contain)
CASES = {
    "sweep": [(["sweep", "{missing}", "--out", "{dir}"], 1, "cannot read the file"),
              (["sweep", "{rec}", "--out", "{dir}"], 1, "unknown spec format '.csv'"),
              (["sweep"], 2, "the following arguments are required: spec, --out")],
    "montecarlo": [(["montecarlo", "nope", "--samples", "2", "--vary", "A1=normal(1,0.1)", "--out", "{dir}"], 1,
                    "unknown scenario 'nope'"),
                   (["montecarlo", "pam-ukf", "--samples", "-1", "--vary", "A1=normal(1,0.1)", "--out", "{dir}"],
                    1, "whole number >= 1; found -1"),
                   (["montecarlo", "pam-ukf", "--samples", "2", "--vary", "A1=weird(1)", "--out", "{dir}"], 1,
                    "unknown law 'weird'"),
                   (["montecarlo", "pam-ukf", "--samples", "2", "--vary", "NOPE=normal(1,0.1)", "--out", "{dir}"],
                    1, "has no parameter 'NOPE'")],
    "diagnose-batch": [(["diagnose-batch", "nope", "{rec}", "--output", "x=pos", "--out", "{dir}"], 1,
                        "unknown model 'nope'"),
                       (["diagnose-batch", "mass-spring-damper", "{nomatch}", "--output", "x=pos", "--out", "{dir}"],
                        1, "no recording matches"),
                       (["diagnose-batch", "mass-spring-damper"], 2, "the following arguments are required")],
    "list": [(["list", "extra"], 2, "unrecognized arguments: extra"),
             (["list", "--json"], 2, "unrecognized arguments: --json"),
             (["lst"], 2, "invalid choice: 'lst'")],
    "equations": [(["equations", "nope"], 1, "unknown model 'nope'"),
                  (["equations", "{missing}"], 1, "missing.json' does not exist"),
                  (["equations", "rlc", "--json", "--at", "V=abc"], 1, "--at V='abc': not a number"),
                  (["equations", "rlc", "--json", "--at", "Q=1"], 1, "unknown variable 'Q'")],
    "draw": [(["draw", "nope", "-o", "{png}"], 1, "unknown model 'nope'"),
             (["draw", "rlc", "-o", "g.txt"], 1, "'g.txt'"),
             (["draw", "rlc"], 2, "-o/--output")],
    "simulate": [(["simulate", "rlc", "--stop-time", "-1", "-o", "{out}"], 1, "t_span: expected finite t0 < t1"),
                 (["simulate", "rlc", "--stop-time", "abc", "-o", "{out}"], 2, "invalid float value: 'abc'"),
                 (["simulate", "rlc", "--stop-time", "1e9", "--output-interval", "1e-6", "-o", "{out}"], 1,
                  "1e+15 samples"),
                 (["simulate", "rlc", "--stop-time", "1", "--output-interval", "0", "-o", "{out}"], 1,
                  "output_interval: expected a positive number"),
                 (["simulate", "rlc", "--stop-time", "1", "--input", "Q=1", "-o", "{out}"], 1, "unknown input 'Q'"),
                 (["simulate", "rlc", "--stop-time", "1", "--param", "R=abc", "-o", "{out}"], 1,
                  "--param R='abc': not a number"),
                 (["simulate", "{missing}", "--stop-time", "1", "-o", "{out}"], 1, "missing.json' does not exist"),
                 (["simulate", "rlc", "--stop-time", "0.01", "-o", "{nodir}"], 1, "o.csv")],
    "compare": [(["compare", "nope"], 2, "invalid choice: 'nope'"),
                (["compare"], 2, "the following arguments are required: model"),
                (["compare", "pam", "--plot"], 2, "expected one argument")],
    "export-fmu": [(["export-fmu", "nope", "-o", "{fmu}"], 1, "unknown model 'nope'"),
                   (["export-fmu", "rlc", "-o", "{fmu}", "--fmi", "4"], 2, "invalid choice: 4"),
                   (["export-fmu", "rlc", "-o", "{fmu}", "--solver-step", "-1"], 1, "solver_step"),
                   (["export-fmu", "rlc", "-o", "{fmu}", "--param", "R_nope=1"], 1, "R_nope")],
    "fmu-info": [(["fmu-info", "{missing}"], 1, "missing.json"),
                 (["fmu-info", "{bad}"], 1, "bad.fmu' is not an FMU"),
                 (["fmu-info"], 2, "the following arguments are required: fmu")],
    "cosim": [(["cosim", "nope"], 1, "unknown scenario 'nope'"),
              (["cosim", "pam-pi", "--plot"], 2, "expected one argument"),
              (["cosim", "pam-pi", "--bogus"], 2, "unrecognized arguments: --bogus")],
    "diagnose": [(["diagnose", "nope", "{rec}", "--output", "x=pos"], 1, "unknown model 'nope'"),
                 (["diagnose", "mass-spring-damper", "{missing}", "--output", "x=pos"], 1, "missing.json"),
                 (["diagnose", "mass-spring-damper", "{rec}", "--input", "F=force", "--output", "x=nocol"], 1,
                  "nocol"),
                 (["diagnose", "mass-spring-damper", "{rec}", "--output", "x=pos", "--holdout", "abc"], 2,
                  "invalid float value: 'abc'")],
    "demo": [(["demo", "--output-dir", "{taken}", "--quick"], 1, "taken"),
             (["demo", "--bogus"], 2, "unrecognized arguments: --bogus"),
             (["demo", "extra"], 2, "unrecognized arguments: extra")],
}
PARAMS = [(command, i, *case) for command, cases in CASES.items() for i, case in enumerate(cases)]


def test_every_subcommand_is_covered():
    from bondcosim.cli import _COMMANDS
    assert set(CASES) == set(_COMMANDS)
    assert all(len(cases) >= 3 for cases in CASES.values())


@pytest.mark.parametrize("command, i, argv, status, text", PARAMS, ids=[f"{c}-{i}" for c, i, *_ in PARAMS])
def test_bad_input_gives_one_line_naming_the_culprit(command, i, argv, status, text, files, capsys):
    argv = [a.format(**files) for a in argv]
    if status == 2:
        with pytest.raises(SystemExit) as exit_info:
            main(argv)
        got = exit_info.value.code
    else:
        got = main(argv)
    err = capsys.readouterr().err
    assert got == status, err
    assert "Traceback" not in err, err
    # progress lines (diagnose: [  0.0 s] step) may come first; the failure is one line, the last
    last = err.splitlines()[-1]
    assert err.endswith("\n") and [line for line in err.splitlines() if line.startswith("bondcosim")] == [last], err
    assert text in last, err


def _run(args, tmp_path):
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    proc = subprocess.Popen([sys.executable, "-m", "bondcosim.cli", *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, cwd=tmp_path, env=env)
    proc.stdout.close()        # the reader goes away before reading anything (as `| head -0`)
    err = proc.stderr.read().decode()
    proc.stderr.close()
    return proc.wait(timeout=300), err


@pytest.mark.parametrize("args", [["list"], ["equations", "pam-locked"], ["cosim", "--list"],
                                  ["simulate", "rlc", "--stop-time", "0.01", "-o", "o.csv"]],
                         ids=lambda a: a[0])
def test_a_closed_pipe_is_quiet(args, tmp_path):
    status, err = _run(args, tmp_path)
    assert err == "" and status == 141


def test_fmu_info_into_a_closed_pipe_is_quiet(tmp_path):
    assert main(["export-fmu", "rlc", "-o", str(tmp_path / "rlc.fmu")]) == 0
    status, err = _run(["fmu-info", "rlc.fmu"], tmp_path)
    assert err == "" and status == 141
