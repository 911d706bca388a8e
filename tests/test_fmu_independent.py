"""The new FMUs (sources, guards, units, event indicators, directional derivatives, the
Dormand-Prince solver) through tools this project did not write, each skipped cleanly
where its package is absent:

* FMU Manipulation Toolbox's checker (``fmu-manipulation-toolbox`` 2.0, ``fmutool -check``):
  the official FMI 2.0/3.0 XSD schemas and its semantic rules;
* ``fmi-bd2cmake`` 0.1.0 and CMake: a build of the FMI 3.0 source FMU from its
  ``buildDescription.xml`` alone;
* libcosim (``libcosimpy`` 0.0.6, FMI 2.0) and Ecos (``ecospy`` 0.7.2, FMI 2.0 and 3.0,
  needs the system's ``libtbb12``): co-simulation masters that must reproduce fmpy's run
  of the same FMU to rounding.
"""
from __future__ import annotations

import importlib.util
import logging
import os
import shutil
import subprocess
import sys
import zipfile

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu

T, DT = 0.2, 1e-3
INPUTS = {"u1": 7.0, "u2": 3.0}
#: (model, export options): sampled friction (RK4, guards), Dormand-Prince with 52 event
#: indicators, an algebraic loop, the stiff exoskeleton with deg/rad units
CASES = [("pam", {}), ("pam-locked", {"solver": "dopri", "tolerance": 1e-9}),
         ("resistor-loop-nl", {}), ("exoskeleton", {"solver": "dopri"})]


def _ecos_loads() -> bool:
    if importlib.util.find_spec("ecospy") is None:
        return False
    try:
        import ecospy  # noqa: F401  -- loads libecos, which needs libtbb.so.12
    except OSError:
        return False
    return True


@pytest.fixture(scope="module")
def fmus(exported_fmu):
    return exported_fmu


def _fmpy_reference(path, names):
    res = simulate_fmu(str(path), stop_time=T, output_interval=DT, start_values=INPUTS,
                       output=list(names))
    return np.array([res[n][-1] for n in names])


@pytest.mark.skipif(importlib.util.find_spec("fmu_manipulation_toolbox") is None,
                    reason="fmu-manipulation-toolbox not installed")
@pytest.mark.parametrize("version", (2, 3))
@pytest.mark.parametrize("model, options", CASES)
def test_fmu_manipulation_toolbox_checker_finds_nothing(fmus, model, options, version, caplog):
    from fmu_manipulation_toolbox.checker import get_checkers
    from fmu_manipulation_toolbox.operations import FMU
    path = fmus(model, version, **options)
    fmu = FMU(str(path))
    try:
        with caplog.at_level(logging.INFO, logger="fmu_manipulation_toolbox"):
            for checker in get_checkers():
                fmu.apply_operation(checker())
    finally:
        fmu.close()
    errors = [r.getMessage() for r in caplog.records if r.levelno >= logging.ERROR]
    assert errors == []
    text = caplog.text
    assert f"compliant with FMI-{version}.0" in text and f"No semantic error against the FMI-{version}" in text


@pytest.mark.skipif(importlib.util.find_spec("libcosimpy") is None, reason="libcosimpy not installed")
@pytest.mark.parametrize("model, options", [c for c in CASES if c[0].startswith("pam")])
def test_libcosim_runs_the_fmu_as_fmpy_does(fmus, model, options):
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave
    path = fmus(model, 2, **options)
    names = ["P_1", "P_2"]
    vr = {v.name: v.valueReference for v in read_model_description(str(path)).modelVariables}
    execution = CosimExecution.from_step_size(step_size=round(DT * 1e9))
    index = execution.add_local_slave(local_slave=CosimLocalSlave(fmu_path=str(path), instance_name="plant"))
    for name, value in INPUTS.items():
        execution.real_initial_value(slave_index=index, variable_reference=vr[name], value=value)
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer=observer)
    assert execution.simulate_until(target_time=round(T * 1e9))
    got = np.array(observer.last_real_values(slave_index=index, variable_references=[vr[n] for n in names]))
    ref = _fmpy_reference(path, names)
    assert np.allclose(got, ref, rtol=1e-13, atol=0) and got[0] > 1.1e5   # muscle 1 filled


@pytest.mark.skipif(not _ecos_loads(), reason="ecospy not installed or its libtbb missing")
@pytest.mark.parametrize("version", (2, 3))
@pytest.mark.parametrize("model, options", [c for c in CASES if c[0].startswith("pam")])
def test_ecos_runs_the_fmu_as_fmpy_does(fmus, model, options, version):
    from ecospy import EcosSimulation, EcosSimulationStructure
    path = fmus(model, version, **options)
    names = ["P_1", "P_2"]
    structure = EcosSimulationStructure()
    structure.add_model("plant", str(path))
    structure.add_parameter_set("inputs", {f"plant::{k}": v for k, v in INPUTS.items()})
    with EcosSimulation(structure=structure, step_size=DT) as sim:
        sim.init(parameter_set="inputs")
        sim.step(round(T / DT))   # (step_until(0.2) stops at 0.199: Ecos sums its steps)
        assert sim.get_time() == pytest.approx(T, abs=1e-12)
        got = np.array([sim.get_real(f"plant::{n}") for n in names])
    ref = _fmpy_reference(path, names)
    assert np.allclose(got, ref, rtol=1e-13, atol=0) and got[0] > 1.1e5


@pytest.mark.skipif(importlib.util.find_spec("fmi_bd2cmake") is None or shutil.which("cmake") is None,
                    reason="fmi-bd2cmake or cmake not installed")
def test_fmi_bd2cmake_builds_the_fmi3_source_fmu(fmus, tmp_path):
    # fmi-bd2cmake (PyPI) writes a CMakeLists.txt from sources/buildDescription.xml alone;
    # CMake builds it with its own flags; the rebuilt FMU runs as the shipped one.
    path = fmus("pam-locked", 3, solver="dopri", tolerance=1e-9)
    root = tmp_path / "unzipped"
    with zipfile.ZipFile(path) as z:
        z.extractall(root)
    env = {"PATH": os.environ["PATH"]}
    steps = ([sys.executable, "-m", "fmi_bd2cmake.cli"],
             ["cmake", "-B", "build", f"-DFMI_HEADERS_DIR={root / 'sources'}", "."],
             ["cmake", "--build", "build"])
    for cmd in steps:
        proc = subprocess.run(cmd, cwd=root, env=env, capture_output=True, text=True, timeout=600)
        assert proc.returncode == 0, (cmd, proc.stdout[-2000:], proc.stderr[-2000:])
    built = root / "build" / "binaries" / "x86_64-linux" / "pam_locked.so"
    shutil.copy(built, root / "binaries" / "x86_64-linux" / "pam_locked.so")
    rebuilt = tmp_path / "rebuilt.fmu"
    with zipfile.ZipFile(rebuilt, "w") as z:
        for f in root.rglob("*"):
            if f.is_file() and "build" not in f.relative_to(root).parts:
                z.write(f, f.relative_to(root).as_posix())
    names = ["P_1", "P_2"]
    assert np.allclose(_fmpy_reference(rebuilt, names), _fmpy_reference(path, names), rtol=1e-12, atol=0)
