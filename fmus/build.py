"""Compile an FMU's shared library from generated files and the fixed wrappers in ``fmus/c/``.

Builds are cached in :func:`bondgraph.numerics.c_build.cache_dir` by the sha256 of
every source file, the compiler and the flags, so exporting the same model
twice compiles once.
"""
from __future__ import annotations

import hashlib
import os
import subprocess
import tempfile
from pathlib import Path

from bondgraph.numerics.c_build import cache_dir, find_compiler
from fmus.errors import CompilationError

__all__ = ["compile_fmu_binary", "fmi_headers", "fixed_sources", "fmi_header_files", "WRAPPERS",
           "FMU_CFLAGS", "FMI_HEADERS"]

#: Directory of the fixed C sources (``bc_fmu_core.h``, ``fmi2_wrapper.c``, ``fmi3_wrapper.c``).
C_DIR = Path(__file__).with_name("c")
WRAPPERS = {2: "fmi2_wrapper.c", 3: "fmi3_wrapper.c"}
#: Hidden visibility: only the FMI functions (marked ``FMI2_Export``/``FMI3_Export``) are exported.
#: -DBC_GLIBC_COMPAT: bind exp/log/pow to their GLIBC_2.2.5 versions (see ``c/bc_platform.h``).
FMU_CFLAGS = ("-O2", "-fno-tree-slp-vectorize", "-shared", "-fPIC", "-fvisibility=hidden",
              "-DBC_GLIBC_COMPAT")


#: The official FMI headers a wrapper includes, per FMI version.
FMI_HEADERS = {2: ("fmi2Functions.h", "fmi2FunctionTypes.h", "fmi2TypesPlatform.h"),
               3: ("fmi3Functions.h", "fmi3FunctionTypes.h", "fmi3PlatformTypes.h")}


def fixed_sources(fmi_version: int) -> dict[str, str]:
    """The hand-written C files of an FMU of `fmi_version`: name -> text (the wrapper,
    ``bc_fmu_core.h``, ``bc_adaptive.h``, ``bc_partials.h``, ``bc_platform.h``)."""
    return {name: (C_DIR / name).read_text()
            for name in ("bc_platform.h", "bc_fmu_core.h", "bc_adaptive.h", "bc_partials.h",
                         WRAPPERS[fmi_version])}


def fmi_header_files(fmi_version: int) -> dict[str, str]:
    """The official FMI headers of `fmi_version` (from fmpy): name -> text."""
    root = fmi_headers()
    return {name: (root / name).read_text() for name in FMI_HEADERS[fmi_version]}


def fmi_headers() -> Path:
    """The official FMI 2.0/3.0 C headers shipped with fmpy."""
    import fmpy
    path = Path(fmpy.__file__).with_name("c-code")
    if not (path / "fmi2Functions.h").exists():
        raise CompilationError(f"fmpy's FMI headers are missing (looked in {path})")
    return path


def compile_fmu_binary(generated: dict[str, str], *, fmi_version: int, identifier: str) -> bytes:
    """Compile the wrapper of `fmi_version` with the `generated` files; return the library's bytes.

    Parameters
    ----------
    generated : mapping file name -> text
        ``model.h`` and ``model_kernels.c``.
    fmi_version : {2, 3}
    identifier : str
        ``modelIdentifier`` (only for messages: the cache is content-addressed).

    Returns
    -------
    bytes

    Raises
    ------
    CompilationError
        No compiler, or it failed (its output attached).
    """
    compiler = find_compiler()
    if compiler is None:
        raise CompilationError("no C compiler found: set $CC or put cc/gcc/clang on PATH")
    wrapper = WRAPPERS[fmi_version]
    fixed = fixed_sources(fmi_version)
    files = {**fixed, **generated}
    key = hashlib.sha256("\0".join([compiler, *FMU_CFLAGS, *(f"{k}\0{files[k]}" for k in sorted(files))])
                         .encode()).hexdigest()[:40]
    target = cache_dir() / f"fmu_{key}.so"
    if target.exists():
        return target.read_bytes()
    target.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=target.parent, prefix=".fmu-") as tmp:
        for name, text in files.items():
            Path(tmp, name).write_text(text)
        lib = Path(tmp, f"{identifier}.so")
        cmd = [compiler, *FMU_CFLAGS, f"-I{tmp}", f"-I{fmi_headers()}", "-o", str(lib),
               str(Path(tmp, wrapper)), "-lm"]
        try:
            proc = subprocess.run(cmd, capture_output=True, text=True, timeout=900)
        except (OSError, subprocess.TimeoutExpired) as exc:
            raise CompilationError(f"could not run {' '.join(cmd)}: {exc}") from None
        if proc.returncode != 0:
            raise CompilationError(f"C compiler failed on the FMU of {identifier!r} "
                                   f"(exit {proc.returncode}): {' '.join(cmd)}",
                                   output=(proc.stdout + proc.stderr).strip())
        os.replace(lib, target)
    return target.read_bytes()
