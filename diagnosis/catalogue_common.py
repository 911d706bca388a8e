"""Shared pieces of the candidate catalogue: parameter specs, fresh names, and what a junction
is (its elements, energy domain and units).

Candidates are built through the graph-editing API (:mod:`bondgraph.editing`) by the kinds of
:mod:`diagnosis.kinds`; each result is a new, ordinary :class:`~bondgraph.BondGraph` that saves,
derives and exports like any other.  Candidate parameters become graph-wide parameters, so a
compiled candidate model can be re-run with new values without being rebuilt.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from bondgraph.params import DOMAINS

from .errors import DiagnosisError

__all__ = ["RELEASED", "released", "ParamSpec", "priced", "fresh_name", "junction_elements", "junction_domain",
           "junction_units", "domain_units", "unit_domain", "P_ATMOSPHERE", "pneumatic_ambient", "ambient_effort"]


#: The value of a limit with no evidence behind it (a saturation side no training sample
#: reaches): "no limit", finite because simulations refuse infinite parameters.
RELEASED = 1e300


def released(value: float) -> bool:
    """Whether a limit's `value` is :data:`RELEASED` (either sign)."""
    return abs(float(value)) >= RELEASED


@dataclass(frozen=True)
class ParamSpec:
    """A fitted parameter of a candidate.

    Parameters
    ----------
    name : str
        Graph parameter name (unique in the candidate graph).
    guess : float
        Starting value, in `unit`.
    lower, upper : float
        Bounds, in `unit` (``lower <= guess <= upper``).
    unit : str
        SI unit.
    description : str
        What it is, in words.
    priced : bool
        Whether the choice of a model prices it (:func:`diagnosis.fit.choose`): a shape that adds
        no physics (the smoothing of a friction's sign, :mod:`diagnosis.kinds.friction_common`)
        is fitted but not counted.
    """

    name: str
    guess: float
    lower: float
    upper: float
    unit: str
    description: str
    priced: bool = True

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name.isidentifier():
            raise DiagnosisError(f"parameter name {self.name!r} is not a valid identifier")
        values = (self.guess, self.lower, self.upper)
        if not all(isinstance(v, (int, float)) and math.isfinite(v) for v in values):
            raise DiagnosisError(f"parameter {self.name!r}: guess and bounds must be finite numbers, "
                                 f"got guess={self.guess!r}, lower={self.lower!r}, upper={self.upper!r}")
        if not self.lower <= self.guess <= self.upper or self.lower == self.upper:
            raise DiagnosisError(f"parameter {self.name!r}: need lower < upper and lower <= guess <= upper, "
                                 f"got {self.lower} <= {self.guess} <= {self.upper} {self.unit}")

    def clipped(self, value: float) -> float:
        """`value` within the bounds."""
        return float(min(max(value, self.lower), self.upper))

    @property
    def magnitude(self) -> bool:
        """Whether this is a magnitude: bounded below by 0, where 0 is no effect, and guessed above it
        (a friction level, a leak coefficient, a lag)."""
        return self.lower == 0 and self.guess > 0


def priced(specs) -> int:
    """How many of the parameters `specs` the choice of a model prices (:attr:`ParamSpec.priced`)."""
    return sum(1 for spec in specs if getattr(spec, "priced", True))


def fresh_name(taken, base: str) -> str:
    """`base`, or `base_2`, `base_3`... whichever is not in `taken`."""
    if base not in taken:
        return base
    k = 2
    while f"{base}_{k}" in taken:
        k += 1
    return f"{base}_{k}"


def junction_elements(graph, junction: str) -> list[tuple[object, object]]:
    """(element, bond) pairs of the elements bonded to `junction`."""
    out = []
    for bond, end in graph.bonds_of(junction):
        other = bond.head.element if end == "tail" else bond.tail.element
        out.append((graph.elements[other], bond))
    return out


def junction_domain(graph, junction: str) -> str:
    """Energy domain of a junction, from the one-ports bonded to it ("generic" if none says)."""
    for element, _ in junction_elements(graph, junction):
        dom = getattr(element, "domain", None)
        if dom in DOMAINS and dom != "generic":
            return dom
    return "generic"


def domain_units(dom: str) -> tuple[str, str]:
    """(effort unit, flow unit) of a domain."""
    d = DOMAINS[dom]
    return d.effort, d.flow


def unit_domain(unit: str, quantity: str) -> str:
    """The energy domain whose `quantity` (a :class:`~bondgraph.params.Domain` field: ``"effort"``,
    ``"resistance"``, ...) is measured in `unit`; ``""`` for none (a generic model's empty unit, or
    one two domains share, as the pressure of the hydraulic and pneumatic ones).  A candidate's
    explanation knows its parameters' units, not its junction's domain."""
    names = [d.name for d in DOMAINS.values() if unit and getattr(d, quantity) == unit]
    return names[0] if len(names) == 1 else ""


def junction_units(graph, junction: str) -> tuple[str, str]:
    """(effort unit, flow unit) at a junction: its domain's, else those of outputs that read
    one of its bonds' effort / flow (``e_<bond>``, ``f_<bond>``), else ("", "")."""
    effort, flow = domain_units(junction_domain(graph, junction))
    bonds = {b.name for b, _ in graph.bonds_of(junction)}
    for out in graph.outputs.values():
        text = str(out.expression).strip()
        if not effort and text.startswith("e_") and text[2:] in bonds:
            effort = out.unit
        if not flow and text.startswith("f_") and text[2:] in bonds:
            flow = out.unit
    return effort, flow


#: the atmosphere's pressure, Pa: where an absolute pneumatic pressure vents to
P_ATMOSPHERE = 101325.0


def pneumatic_ambient(effort) -> float:
    """Where a pneumatic junction of pressure `effort` (along the run) vents to: the atmosphere
    (:data:`P_ATMOSPHERE`) where the mean pressure exceeds 50 kPa (absolute pressures), else 0
    (gauge pressures, or no data)."""
    e = None if effort is None else np.asarray(effort, dtype=float).ravel()
    return P_ATMOSPHERE if e is not None and e.size and float(np.mean(e)) > 5e4 else 0.0


def ambient_effort(graph, junction: str, effort) -> float:
    """The effort a leak from `junction` flows towards, given the junction's effort along the run.

    * pneumatic: :func:`pneumatic_ambient`;
    * thermal: the ambient the model itself names, the temperature of a thermal effort source (of
      several, the one nearest the junction's first temperature), else that first temperature (the
      plant at rest at its ambient when the record starts).  Heat leaks to the room, not to 0 K: a
      heater block's leak towards 0 K had been a constant heat loss of 0.057 W with it;
    * any other domain: 0 (an electrical ground, a hydraulic tank at gauge pressure).
    """
    dom = junction_domain(graph, junction)
    if dom == "pneumatic":
        return pneumatic_ambient(effort)
    e = None if effort is None else np.asarray(effort, dtype=float).ravel()
    if dom != "thermal":
        return 0.0
    first = float(e[0]) if e is not None and e.size else None
    defaults = {d.name: d.default for d in graph.inputs()}
    sources = [float(defaults[el.input]) for el in graph.elements.values()
               if el.kind == "Se" and el.domain == "thermal"]
    if sources:
        return sources[0] if first is None else min(sources, key=lambda v: abs(v - first))
    return 0.0 if first is None else first
