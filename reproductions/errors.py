"""Exceptions of the reproductions layer (``reproductions``).

Every class derives from :class:`bondgraph.errors.BondcosimError` and from the
builtin it refines.  The co-simulation errors a scenario passes on are
re-exported from :mod:`cosim.errors`; modules of this package import their
errors from here.
"""
from __future__ import annotations

from cosim.errors import BondcosimError, CosimError, ParameterError, UnknownNameError

__all__ = ["BondcosimError", "CosimError", "ParameterError", "UnknownNameError", "ScenarioError"]


class ScenarioError(CosimError):
    """A closed-loop scenario called with a bad argument (a signal of the wrong
    shape, an unknown controller kind); ``name`` is the argument."""

    def __init__(self, message: str, name: str = ""):
        self.name = str(name)
        super().__init__(message)
