"""Exceptions of the co-simulation layer (``cosim``).

Every class derives from :class:`bondgraph.errors.BondcosimError` and from the
builtin it refines.  :class:`CosimError` and :class:`AlgebraicLoopError` are
defined in :mod:`bondgraph.errors` (where existing code imports them from) and
re-exported here; modules of this package import their errors from here.
"""
from __future__ import annotations

from bondgraph.errors import (AlgebraicLoopError, BondcosimError, CompilationError, CosimError, FMUError,
                              FMUStepDiscarded, ParameterError, SimulationError, UnitError, UnknownNameError)

__all__ = ["BondcosimError", "CosimError", "AlgebraicLoopError", "PortTypeError",
           "CompilationError", "FMUError", "FMUStepDiscarded", "ParameterError", "SimulationError", "UnitError",
           "UnknownNameError"]


class PortTypeError(BondcosimError, TypeError):
    """A port given as something other than a Port or a name (``given``: its repr)."""

    def __init__(self, message: str, given: str = ""):
        self.given = given
        super().__init__(message)
