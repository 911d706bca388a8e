"""Exceptions of the estimator layer (``estimators``).

Every class derives from :class:`bondgraph.errors.BondcosimError` and from the
builtin it refines.  :class:`EstimatorError` and the mode errors are defined
in :mod:`bondgraph.errors` (where existing code imports them from) and
re-exported here; modules of this package import their errors from here.
"""
from __future__ import annotations

from bondgraph.errors import (BondcosimError, EstimatorError, UncontrollableModeError, UnknownNameError,
                              UnobservableModeError)

__all__ = ["BondcosimError", "EstimatorError", "UnobservableModeError", "UncontrollableModeError",
           "UnknownNameError", "UnknownStateError"]


class UnknownStateError(UnknownNameError, KeyError):
    """A state name an estimate does not have (``result["nope"]``): an
    :class:`UnknownNameError` and a ``KeyError``, as mapping lookups raise."""

    def __str__(self) -> str:   # KeyError would quote the message
        return Exception.__str__(self)
