"""Exceptions of the FMU layer (``fmus``).

Every class derives from :class:`bondgraph.errors.BondcosimError` and from the
builtin it refines.  :class:`FMUError` and :class:`CompilationError` are
defined in :mod:`bondgraph.errors` (where existing code imports them from) and
re-exported here; modules of this package import their errors from here.
"""
from __future__ import annotations

from bondgraph.errors import (ArgumentError, ArgumentTypeError, BondcosimError, CompilationError, DerivationError,
                              FMUError, MissingFileError, ParameterError, UnitError, UnknownNameError)

__all__ = ["BondcosimError", "FMUError", "CompilationError", "DerivationError", "FMUFileNotFoundError", "FMUModelTypeError",
           "ArgumentError", "ArgumentTypeError", "MissingFileError", "ParameterError", "UnitError",
           "UnknownNameError"]


class FMUFileNotFoundError(FMUError, FileNotFoundError):
    """An FMU file that does not exist (``path``: the file)."""


class FMUModelTypeError(BondcosimError, TypeError):
    """Export was given something that is neither a BondGraph nor StateEquations.

    Attributes
    ----------
    given : str
        The type name of what was given.
    """

    def __init__(self, message: str, given: str = ""):
        self.given = given
        super().__init__(message)
