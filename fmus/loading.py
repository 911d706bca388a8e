"""Opening FMUs that anybody made: model description, unzipping, variable look-up.

Every failure is an :class:`~bondgraph.errors.FMUError` naming the file and
what is wrong with it (missing, not a zip archive, no or unreadable
``modelDescription.xml``), or an :class:`~bondgraph.errors.UnknownNameError`
listing the variables the FMU has; never a traceback from inside zipfile,
lxml or fmpy.
"""
from __future__ import annotations

import os
import shutil
import tempfile
import zipfile
from pathlib import Path

from fmus.errors import FMUError, FMUFileNotFoundError, UnknownNameError

__all__ = ["read_fmu", "extract_fmu", "remove_extracted", "find_variable", "variable_unit"]


def _check_archive(path: Path) -> None:
    if not path.exists():
        raise FMUFileNotFoundError(f"FMU file {str(path)!r} does not exist", path)
    if path.is_dir():
        raise FMUError(f"{str(path)!r} is a directory; expected an .fmu file (a zip archive)",
                       path)
    if not zipfile.is_zipfile(path):
        raise FMUError(f"{str(path)!r} is not an FMU: not a zip archive", path)
    try:
        with zipfile.ZipFile(path) as zf:
            names = zf.namelist()
            bad = zf.testzip()
    except (zipfile.BadZipFile, OSError, EOFError) as exc:
        raise FMUError(f"{str(path)!r} is a corrupt zip archive: {exc}", path) from None
    if bad is not None:
        raise FMUError(f"{str(path)!r} is a corrupt zip archive: member {bad!r} fails its CRC "
                       "check", path)
    if "modelDescription.xml" not in names:
        listed = ", ".join(names[:8]) + (", ..." if len(names) > 8 else "")
        raise FMUError(f"{str(path)!r} is not an FMU: the archive has no modelDescription.xml "
                       f"at its top level (it holds {listed or 'nothing'})", path)


def read_fmu(path):
    """Read and validate the model description of an FMU.

    Parameters
    ----------
    path : str or os.PathLike
        The ``.fmu`` file.

    Returns
    -------
    fmpy.model_description.ModelDescription

    Raises
    ------
    FMUError
        The file is missing, is not a (sound) zip archive, has no
        ``modelDescription.xml``, or the XML is malformed or invalid; the
        message names the file and the problem(s).
    """
    from fmpy import read_model_description
    from fmpy.model_description import ValidationError

    path = Path(os.fspath(path))
    _check_archive(path)
    try:
        return read_model_description(str(path))
    except ValidationError as exc:
        problems = "\n".join(f"  - {p}" for p in exc.problems)
        raise FMUError(f"{str(path)!r}: invalid modelDescription.xml:\n{problems}", path) from None
    except Exception as exc:   # lxml syntax errors, unsupported versions (fmpy raises Exception)
        raise FMUError(f"{str(path)!r}: cannot read modelDescription.xml: "
                       f"{type(exc).__name__}: {exc}", path) from None


def extract_fmu(path) -> Path:
    """Unzip an FMU into a new temporary directory.

    Parameters
    ----------
    path : str or os.PathLike
        The ``.fmu`` file (checked as by :func:`read_fmu`).

    Returns
    -------
    pathlib.Path
        The directory; the caller removes it with :func:`remove_extracted`.

    Raises
    ------
    FMUError
        As :func:`read_fmu`, or when the archive cannot be written out.
    """
    path = Path(os.fspath(path))
    _check_archive(path)
    directory = Path(tempfile.mkdtemp(prefix=f"bondcosim_{path.stem}_"))
    try:
        with zipfile.ZipFile(path) as zf:
            zf.extractall(directory)
    except (OSError, zipfile.BadZipFile) as exc:
        shutil.rmtree(directory, ignore_errors=True)
        raise FMUError(f"{str(path)!r}: cannot unzip into {directory}: {exc}", path) from None
    return directory


def remove_extracted(directory) -> None:
    """Remove a directory made by :func:`extract_fmu` (no error if already gone)."""
    shutil.rmtree(directory, ignore_errors=True)


def find_variable(md, name: str, *, path=""):
    """The model variable called `name`.

    Parameters
    ----------
    md : fmpy.model_description.ModelDescription
    name : str
    path : str or os.PathLike, optional
        The FMU file, named in the error.

    Returns
    -------
    fmpy.model_description.ModelVariable

    Raises
    ------
    UnknownNameError
        ``kind="FMU variable"``, with every variable name of the FMU as
        ``known``.
    """
    for variable in md.modelVariables:
        if variable.name == name:
            return variable
    model = md.modelName + (f" ({path})" if str(path) else "")
    raise UnknownNameError("FMU variable", name, [v.name for v in md.modelVariables], model)


def variable_unit(variable) -> str:
    """Unit of a model variable: its own ``unit``, else its declared type's, else ``""``."""
    if getattr(variable, "unit", None):
        return variable.unit
    declared = getattr(variable, "declaredType", None)
    return getattr(declared, "unit", None) or ""
