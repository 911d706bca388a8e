"""The ``sources/`` folder of an exported FMU: everything needed to rebuild its binary.

An exported FMU is a *source* FMU as well as a binary one.  ``sources/`` holds

* the FMI wrapper of its version (``fmi2_wrapper.c`` / ``fmi3_wrapper.c``) -- the one
  translation unit to compile; it includes the others;
* ``bc_platform.h``, ``bc_fmu_core.h``, ``bc_adaptive.h``, ``bc_partials.h`` (fixed, hand-written), ``model.h`` and
  ``model_kernels.c`` (generated for the model; included, not compiled alone);
* the official FMI headers of its version (BSD-2-Clause, Modelica Association),
  so that nothing outside the FMU is needed;
* for FMI 3.0, ``buildDescription.xml``.

On Linux ``cc -shared -fPIC -O2 [-DBC_GLIBC_COMPAT] -Isources sources/fmi2_wrapper.c -o <id>.so -lm``
builds the library (FMI 2.0 lists the wrapper in ``<SourceFiles>`` of the model
description).
"""
from __future__ import annotations

import xml.etree.ElementTree as ET

from .build import WRAPPERS, fixed_sources, fmi_header_files

__all__ = ["source_files", "compiled_sources", "build_description_xml"]


def compiled_sources(fmi_version: int) -> list[str]:
    """The files an importer compiles (the others are included by them)."""
    return [WRAPPERS[fmi_version]]


def build_description_xml(identifier: str, fmi_version: int = 3) -> str:
    """FMI 3.0's ``sources/buildDescription.xml``: one C99 source file set, the
    ``sources`` folder on the include path, libm."""
    root = ET.Element("fmiBuildDescription", {"fmiVersion": "3.0"})
    config = ET.SubElement(root, "BuildConfiguration", {"modelIdentifier": identifier})
    files = ET.SubElement(config, "SourceFileSet", {"language": "C99"})
    for name in compiled_sources(fmi_version):
        ET.SubElement(files, "SourceFile", {"name": name})
    ET.SubElement(files, "IncludeDirectory", {"name": "."})
    ET.SubElement(config, "Library", {"name": "m", "description": "the C maths library (libm)"})
    ET.indent(root)
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"


def source_files(generated: dict[str, str], *, fmi_version: int, identifier: str) -> dict[str, str]:
    """Path in the FMU -> text of every file under ``sources/``.

    Parameters
    ----------
    generated : mapping file name -> text
        ``model.h`` and ``model_kernels.c``.
    fmi_version : {2, 3}
    identifier : str
        ``modelIdentifier``.

    Returns
    -------
    dict str -> str
    """
    files = {**fixed_sources(fmi_version), **generated, **fmi_header_files(fmi_version)}
    if fmi_version == 3:
        files["buildDescription.xml"] = build_description_xml(identifier, fmi_version)
    return {f"sources/{name}": files[name] for name in sorted(files)}
