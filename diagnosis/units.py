"""Unit conversion of recorded columns into the model's (SI) units.

The grammar lives in :mod:`bondgraph.units` (one unit module for every layer);
this module re-exports it and raises :class:`diagnosis.errors.UnitError` (a
:class:`~diagnosis.errors.DiagnosisError` and a
:class:`bondgraph.errors.UnitError`).

Examples
--------
>>> float(convert(2.0, "bar", "Pa"))
200000.0
>>> convert([90.0, 180.0], "deg", "rad").round(6).tolist()
[1.570796, 3.141593]
"""
from __future__ import annotations

import functools


from bondgraph import units as _units
from bondgraph.units import Unit

from .errors import CoreUnitError, UnitError

__all__ = ["Unit", "parse_unit", "convert", "compatible"]


def _as_diagnosis_error(fn):
    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        try:
            return fn(*args, **kwargs)
        except CoreUnitError as exc:
            if isinstance(exc, UnitError):
                raise
            raise UnitError(str(exc), exc.unit_from, exc.unit_to) from None
    return wrapper


parse_unit = _as_diagnosis_error(_units.parse_unit)
compatible = _as_diagnosis_error(_units.compatible)
convert = _as_diagnosis_error(_units.convert)
