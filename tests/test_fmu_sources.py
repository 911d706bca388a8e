"""Source FMUs (issue 12, part 1): every export ships its C sources under ``sources/``,
FMI 2.0 lists them in ``<SourceFiles>``, FMI 3.0 in ``sources/buildDescription.xml``; the
binary rebuilt from ``sources/`` alone with plain ``cc`` (and with fmpy's own CMake build,
an independent builder) gives bit-identical results in fmpy; the binaries need no glibc
symbol version newer than GLIBC_2.2.5 (exp/log/pow bound to their old versions with
``-DBC_GLIBC_COMPAT``)."""
from __future__ import annotations

import os
import re
import shutil
import subprocess
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy import simulate_fmu
from fmpy.validation import validate_fmu

import plants.library as library
from fmus import export

VERSIONS = (2, 3)
FOLDER = {2: "linux64", 3: "x86_64-linux"}
WRAPPER = {2: "fmi2_wrapper.c", 3: "fmi3_wrapper.c"}


def _unpack(fmu: Path, where: Path) -> Path:
    with zipfile.ZipFile(fmu) as z:
        z.extractall(where)
    return where


def _pack(folder: Path, fmu: Path) -> Path:
    with zipfile.ZipFile(fmu, "w", zipfile.ZIP_DEFLATED) as z:
        for path in sorted(folder.rglob("*")):
            if path.is_file():
                z.write(path, path.relative_to(folder).as_posix())
    return fmu


def _run(fmu: Path):
    # pam with both valves driven: exp/pow/sqrt and the held Kikuuwe friction all run
    return simulate_fmu(str(fmu), stop_time=0.3, output_interval=1e-3,
                        start_values={"u1": 7.0, "u2": 3.0}, output=["psi", "P1", "P2", "tau"])


@pytest.fixture(scope="module")
def pam_fmus(exported_fmu):
    return {v: exported_fmu("pam", v) for v in VERSIONS}


@pytest.mark.parametrize("version", VERSIONS)
def test_sources_are_listed(pam_fmus, version):
    path = pam_fmus[version]
    assert validate_fmu(str(path)) == []
    with zipfile.ZipFile(path) as z:
        names = set(z.namelist())
        md = ET.fromstring(z.read("modelDescription.xml"))
        for f in ("bc_fmu_core.h", "bc_platform.h", "model.h", "model_kernels.c", WRAPPER[version],
                  f"fmi{version}Functions.h", f"fmi{version}FunctionTypes.h"):
            assert f"sources/{f}" in names
        if version == 2:
            listed = [f.get("name") for f in md.find("CoSimulation").find("SourceFiles")]
        else:
            build = ET.fromstring(z.read("sources/buildDescription.xml"))
            config = build.find("BuildConfiguration")
            assert config.get("modelIdentifier") == "pam"
            assert [lib.get("name") for lib in config.iter("Library")] == ["m"]
            listed = [f.get("name") for f in config.iter("SourceFile")]
    assert listed == [WRAPPER[version]]


@pytest.mark.parametrize("version", VERSIONS)
def test_rebuilt_from_sources_alone_with_cc_is_bit_identical(pam_fmus, version, tmp_path):
    cc = shutil.which("cc") or shutil.which("gcc")
    original = pam_fmus[version]
    folder = _unpack(original, tmp_path / "unzipped")
    lib = folder / "binaries" / FOLDER[version] / "pam.so"
    lib.unlink()
    env = {"PATH": os.environ["PATH"]}   # nothing of the project: a bare environment
    proc = subprocess.run([cc, "-shared", "-fPIC", "-O2", "-DBC_GLIBC_COMPAT", "-Isources",
                           f"sources/{WRAPPER[version]}", "-o", str(lib), "-lm"], cwd=folder, env=env, capture_output=True,
                          text=True)
    assert proc.returncode == 0, proc.stderr
    rebuilt = _pack(folder, tmp_path / "rebuilt.fmu")
    assert validate_fmu(str(rebuilt)) == []
    if shutil.which("objdump"):
        out = subprocess.run(["objdump", "-T", str(lib)], capture_output=True, text=True).stdout
        assert set(re.findall(r"GLIBC_([0-9.]+)", out)) == {"2.2.5"}
    a, b = _run(original), _run(rebuilt)
    assert a["P1"][-1] > 1.2e5 > a["P2"][-1]   # the valves fill muscle 1 and vent muscle 2
    for name in ("psi", "P1", "P2", "tau"):
        assert np.array_equal(a[name], b[name]), name


@pytest.mark.skipif(shutil.which("cmake") is None, reason="fmpy's source build needs cmake")
@pytest.mark.parametrize("version", VERSIONS)
def test_fmpy_builds_the_source_fmu(pam_fmus, version, tmp_path):
    from fmpy.build import build_platform_binary
    folder = _unpack(pam_fmus[version], tmp_path / "unzipped")
    shutil.rmtree(folder / "binaries")
    build_dir = tmp_path / "cmake"
    build_dir.mkdir()
    build_platform_binary(folder, build_dir=build_dir)
    assert (folder / "binaries" / FOLDER[version] / "pam.so").exists()
    rebuilt = _pack(folder, tmp_path / "fmpy-built.fmu")
    a, b = _run(pam_fmus[version]), _run(rebuilt)
    for name in ("psi", "P1", "P2", "tau"):
        np.testing.assert_allclose(b[name], a[name], rtol=1e-12, atol=0)


@pytest.mark.skipif(shutil.which("objdump") is None, reason="needs binutils' objdump")
@pytest.mark.parametrize("model", ("pam", "coupled-tanks", "exoskeleton"))
def test_binaries_need_only_old_glibc_symbols(model, tmp_path):
    path = export(library.build(model), tmp_path / f"{model}.fmu")
    lib = _unpack(path, tmp_path / "u") / "binaries" / "linux64"
    out = subprocess.run(["objdump", "-T", str(next(lib.iterdir()))], capture_output=True,
                         text=True, check=True).stdout
    versions = set(re.findall(r"GLIBC_([0-9.]+)", out))
    assert versions == {"2.2.5"}, versions
