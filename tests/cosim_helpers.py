"""Build the hand-written FMU of ``tests/fmus/`` (an FMU this project did not generate).

``handwritten_msd(tmp_path_factory)`` compiles ``handwritten_msd.c`` with gcc
against the FMI headers fmpy ships and zips it with ``handwritten_msd.xml``.
The shared library is compiled once per test session, whichever test module
asks first.
"""
from __future__ import annotations

import re
import shutil
import subprocess
import zipfile
from pathlib import Path

import pytest

SOURCE = Path(__file__).parent / "fmus"
_BUILT: dict = {}


def _compile(directory: Path) -> Path:
    import fmpy
    gcc = shutil.which("gcc")
    if gcc is None:
        pytest.skip("gcc is needed to build the hand-written test FMU")
    lib = directory / "handwritten_msd.so"
    headers = Path(fmpy.__file__).parent / "c-code"
    done = subprocess.run([gcc, "-shared", "-fPIC", "-O2", "-fvisibility=hidden", "-Wall",
                           f"-I{headers}", str(SOURCE / "handwritten_msd.c"), "-o", str(lib), "-lm"],
                          capture_output=True, text=True)
    if done.returncode != 0:
        pytest.fail(f"gcc failed on handwritten_msd.c:\n{done.stderr}")
    return lib


def handwritten_msd(tmp_path_factory, *, declare_dependencies: bool = True) -> Path:
    """Path of the hand-written mass-spring-damper FMU (FMI 2.0 Co-Simulation).

    With ``declare_dependencies=False`` the outputs carry no ``dependencies``
    attribute, so an importer must assume they depend on every input.
    """
    if "lib" not in _BUILT:
        _BUILT["lib"] = _compile(tmp_path_factory.mktemp("msd_build"))
    if declare_dependencies not in _BUILT:
        xml = (SOURCE / "handwritten_msd.xml").read_text()
        if not declare_dependencies:
            xml = re.sub(r' dependencies="[^"]*"', "", xml)
        path = tmp_path_factory.mktemp("msd") / "handwritten_msd.fmu"
        with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as zf:
            zf.writestr("modelDescription.xml", xml)
            zf.write(_BUILT["lib"], "binaries/linux64/handwritten_msd.so")
        _BUILT[declare_dependencies] = path
    return _BUILT[declare_dependencies]
