"""Exceptions of the co-simulation layer (``cosim``).

Every class derives from :class:`bondgraph.errors.BondcosimError` and from the
builtin it refines.  :class:`CosimError` and :class:`AlgebraicLoopError` are
defined in :mod:`bondgraph.errors` (where existing code imports them from) and
re-exported here; modules of this package import their errors from here.
"""
from __future__ import annotations

from bondgraph.errors import (AlgebraicLoopError, BondcosimError, CompilationError, CosimError, FMUError,
                              FMUStepDiscarded, ParameterError, SimulationError, UnitError, UnknownNameError)

__all__ = ["BondcosimError", "CosimError", "AlgebraicLoopError", "ScenarioError", "PortTypeError",
           "CompilationError", "FMUError", "FMUStepDiscarded", "ParameterError", "SimulationError", "UnitError",
           "UnknownNameError"]


class ScenarioError(CosimError):
    """A closed-loop scenario called with a bad argument (a signal of the wrong
    shape, an unknown controller kind); ``name`` is the argument."""

    def __init__(self, message: str, name: str = ""):
        self.name = str(name)
        super().__init__(message)


class PortTypeError(BondcosimError, TypeError):
    """A port given as something other than a Port or a name (``given``: its repr)."""

    def __init__(self, message: str, given: str = ""):
        self.given = given
        super().__init__(message)
