"""Parameters and physical domains.

A :class:`Param` is a named number with a unit and a description.  A
:class:`Domain` gives the units of effort, flow and the stored quantities in
one energy domain, so that a parameter given as a bare number still gets a
unit (an inertia in the rotational domain is in kg m^2).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from .errors import ParameterError

__all__ = ["Param", "Domain", "DOMAINS", "domain", "as_param", "values_with_overrides"]


@dataclass(frozen=True)
class Param:
    """A named model parameter.

    Parameters
    ----------
    name : str
        Symbol name, unique in the graph (a parameter used by two elements is
        the same parameter only if name, value and unit all agree).
    value : float
        Value in SI units.
    unit : str
        Unit of `value`, e.g. ``"N m s/rad"``; ``""`` for dimensionless.
    description : str
        One line saying what the parameter is (and its source).
    min, max : float, optional
        Physical range of `value` (inclusive, same unit), e.g. ``min=0`` for a
        mass; a value outside it is a :class:`ParameterError` here, in
        :func:`bondgraph.numerics.simulate` and when an FMU parameter is set.
    """

    name: str
    value: float
    unit: str = ""
    description: str = ""
    min: float | None = None
    max: float | None = None

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name.isidentifier():
            raise ParameterError(f"parameter name {self.name!r} is not a valid identifier", name=str(self.name))
        value = self.value
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            try:
                value = float(value)
            except (TypeError, ValueError):
                raise ParameterError(
                    f"parameter {self.name!r}: value {self.value!r} is not a number", name=self.name) from None
        if not math.isfinite(float(value)):
            raise ParameterError(f"parameter {self.name!r}: value {value!r} is not finite", name=self.name)
        object.__setattr__(self, "value", float(value))
        for key in ("min", "max"):
            bound = getattr(self, key)
            if bound is not None:
                if isinstance(bound, bool) or not isinstance(bound, (int, float)) or math.isnan(bound):
                    raise ParameterError(f"parameter {self.name!r}: {key} {bound!r} is not a number",
                                         name=self.name)
                object.__setattr__(self, key, float(bound))
        self.check(self.value)

    def check(self, value: float, *, owner: str = "") -> float:
        """`value` if it is finite and inside ``[min, max]``; else a :class:`ParameterError`
        naming the parameter, the value and the range."""
        value = float(value)
        where = f"{owner}: " if owner else ""
        if not math.isfinite(value):
            raise ParameterError(f"{where}parameter {self.name!r}: value {value!r} is not finite",
                                 name=self.name)
        if (self.min is not None and value < self.min) or (self.max is not None and value > self.max):
            unit = f" {self.unit}" if self.unit and self.unit != "1" else ""
            raise ParameterError(f"{where}parameter {self.name!r} = {value!r}{unit} is outside its "
                                 f"physical range [{_bound(self.min)}, {_bound(self.max)}]{unit}",
                                 name=self.name)
        return value

    def to_dict(self) -> dict:
        data = {"name": self.name, "value": self.value, "unit": self.unit,
                "description": self.description}
        data.update({k: getattr(self, k) for k in ("min", "max") if getattr(self, k) is not None})
        return data


def _bound(x: float | None) -> str:
    return "unbounded" if x is None else repr(x)


@dataclass(frozen=True)
class Domain:
    """Units of one energy domain (SI)."""

    name: str
    effort: str
    flow: str
    momentum: str
    displacement: str
    inertance: str
    compliance: str
    stiffness: str
    resistance: str


DOMAINS = {d.name: d for d in (
    Domain("generic", "", "", "", "", "", "", "", ""),
    Domain("translation", "N", "m/s", "N s", "m", "kg", "m/N", "N/m", "N s/m"),
    Domain("rotation", "N m", "rad/s", "N m s", "rad", "kg m^2", "rad/(N m)", "N m/rad", "N m s/rad"),
    Domain("electrical", "V", "A", "Wb", "C", "H", "F", "1/F", "Ohm"),
    Domain("hydraulic", "Pa", "m^3/s", "Pa s", "m^3", "Pa s^2/m^3", "m^3/Pa", "Pa/m^3", "Pa s/m^3"),
    # Pseudo-bond domains: effort x flow is not a power.
    Domain("pneumatic", "Pa", "kg/s", "Pa s", "kg", "1/m", "kg/Pa", "Pa/kg", "Pa s/kg"),
    Domain("thermal", "K", "W", "K s", "J", "K s^2/J", "J/K", "K/J", "K/W"),
)}


def domain(name: str) -> Domain:
    """The :class:`Domain` called `name` (a clear error lists the known ones)."""
    try:
        return DOMAINS[name]
    except KeyError:
        raise ParameterError(
            f"unknown domain {name!r}; expected one of {', '.join(DOMAINS)}", name=str(name)) from None


def as_param(value, name: str, unit: str, description: str = "", *, min: float | None = None) -> Param:
    """`value` as a :class:`Param`: a Param is kept, a number gets `name`, `unit` and `min`."""
    if isinstance(value, Param):
        return value
    return Param(name, value, unit, description, min=min)


def values_with_overrides(params, overrides=None, *, owner: str) -> dict[str, float]:
    """Values of `params` (mapping name -> Param) by name, with `overrides` applied.

    Raises
    ------
    ParameterError
        An override names no parameter (the message lists the known ones) or
        is not a finite number.
    """
    values = {name: p.value for name, p in params.items()}
    overrides = dict(overrides or {})
    unknown = sorted(set(overrides) - set(values))
    if unknown:
        raise ParameterError(f"{owner} has no parameter(s) {', '.join(unknown)}; "
                             f"expected one or more of {', '.join(values)}", name=unknown[0])
    values.update({name: params[name].check(Param(name, value).value, owner=owner)
                   for name, value in overrides.items()})
    return values
