"""Exceptions of the plant layer (``plants``).

Every class derives from :class:`bondgraph.errors.BondcosimError` and from the
builtin it refines; the ones the modelling language defines are re-exported
here, and modules of this package import their errors from here.
"""
from __future__ import annotations

from bondgraph.errors import (ArgumentError, ArgumentTypeError, BondcosimError, GraphError, MissingFileError,
                              ParameterError, SimulationError)

__all__ = ["BondcosimError", "ArgumentError", "ArgumentTypeError", "GraphError", "MissingFileError",
           "ParameterError", "SimulationError", "UnknownModelError", "ModelFileError"]


class UnknownModelError(GraphError):
    """A model name that is neither a built-in model nor a ``.json``/``.py`` file.

    Attributes
    ----------
    name : str
        The name given.
    known : list of str
        The built-in model names.
    """

    def __init__(self, name: str, known, message: str | None = None):
        self.name, self.known = str(name), list(known)
        super().__init__(message or f"unknown model {name!r}: not a built-in model ({', '.join(self.known)}), "
                                    "nor a .json or .py file")


class ModelFileError(GraphError):
    """A ``.py`` model file that fails to import, defines no ``build()``, or builds no BondGraph
    (``path``: the file)."""

    def __init__(self, message: str, path: str = ""):
        self.path = str(path)
        super().__init__(message)
