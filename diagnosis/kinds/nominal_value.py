"""``nominal_value`` of an element at a junction: no physics is missing, the nominal's own value of
a linear I, C or R is off (a mass or inertia from a drawing, an inductance, a stiffness, a capacity
or a resistance from a data sheet), refitted alone.

A model written from a rig's documentation carries values a few per cent off; their error is a
residual like any missing effect's, and without this kind it was answered by one: null recordings
of a mass-spring-damper against a nominal spring 3 % stiff or mass 3 % heavy, of an RLC circuit
against an inductance or a capacitance 3 % off and of a hydraulic circuit against a pipe's
inertance 3 % high all answered a cubic spring (seed 2323).  One candidate per linear I, C or R on
the junction, its one parameter the element's own (refitted under its name by
:meth:`Candidate.build <diagnosis.catalogue.Candidate.build>`), within a factor 3 either way for
an I or a C.  An R's resistance is refitted only the way no other kind goes: down at a 1-junction
(a nominal resistance too low there is the viscous friction the vocabulary adds, e = b f beside
e = R f) and up at a 0-junction (one too high there is a leak, f = e / R beside another flow).
Both ways, the two kinds would be one model and tie on every recording.  An I or a C whose
content does not start at 0 (a heater block's heat, a moving mass's momentum) keeps its start's
effort or flow when refitted (:func:`~diagnosis.kinds.storage_common.held_start`).  A C's value refitted
with a cubic term is ``nonlinear_stiffness``, which the choice's price per parameter tells from
this one.
"""
from __future__ import annotations

import numpy as np

from ..catalogue_common import ParamSpec, junction_elements
from .base import Kind, Proposal, register
from .feature_signals import FeatureGroup
from .storage_common import held_start, held_start_law

#: the factor either way a nominal value may be refitted within
RANGE = 3.0


@register
class NominalValue(Kind):
    name = "nominal_value"
    doors = ("1", "0")
    rewrites_target = False

    def propose(self, site):
        out = []
        for element in _linear_elements(site.graph, site.name):
            v = float(element.value.value)
            lower, upper = v / RANGE, v * RANGE
            if element.kind == "R":     # only the way no other kind goes (module docstring)
                lower, upper = (lower, v) if site.door == "1" else (v, upper)
            out.append(Proposal(target=element.name, params=(
                ParamSpec(element.value.name, v, lower, upper, element.value.unit,
                          f"{_quantity(element)} of {element.name} (refitted)"),),
                constants=held_start(site, element) if element.kind != "R" else ()))
        return out

    def build(self, graph, cand, values):
        """`graph` itself: the value is refitted under the element's own parameter name; an I or
        a C whose content starts off 0 gets the law that holds its start's effort or flow."""
        if not cand.constants:
            return graph
        return graph.with_law(cand.target, lambda old, x: held_start_law(old, x, cand.constants))

    def explain(self, cand, values, show):
        spec = cand.params[0]
        value, nominal = values.get(spec.name, spec.guess), spec.guess
        change = 100.0 * (value / nominal - 1.0) if nominal else float("nan")
        quantity = spec.description.replace(" (refitted)", "")
        was = f"{nominal:.4g} {spec.unit if spec.unit != '1' else ''}".strip()
        return (f"the {quantity} at {cand.place.name} is {show(spec.name)}, {abs(change):.3g} % "
                f"{'above' if change >= 0 else 'below'} its nominal {was} (no physics is missing there): "
                f"a wrong nominal value of {cand.target}")


def value_columns(graph, junction: str, signals) -> FeatureGroup | None:
    """What the I and C values refitted at `junction` add to it, as feature columns for the feature
    regression (:mod:`diagnosis.features`) to fit beside a kind's: a value :math:`\\Delta m` off
    adds the effort :math:`\\Delta m\\,\\dot v` at a 1-junction (an I) or :math:`\\Delta k\\,q` (a C,
    its content q), and the flow :math:`\\Delta C\\,\\dot e` at a 0-junction (a C).  One column per
    distinct signal (two masses on one 1-junction are one column); an I on a 0-junction and the
    R elements have none (an R's value is the viscous friction's or the leak's own column).  None
    when the junction has no such value.  `signals` is the junction's
    :class:`~diagnosis.kinds.feature_signals.FeatureSignals`."""
    columns = {}
    for element in _linear_elements(graph, junction):
        if element.kind == "I" and signals.one:
            columns["dv/dt"] = np.gradient(signals.v, signals.t)
        elif element.kind == "C" and signals.one and f"content:{element.name}" in signals.values:
            columns[f"q({element.name})"] = np.asarray(signals.values[f"content:{element.name}"], float)
        elif element.kind == "C" and not signals.one:
            columns["de/dt"] = np.gradient(np.asarray(signals.values["effort"], float), signals.t)
    if not columns:
        return None
    return FeatureGroup(None, "", list(columns), np.stack(list(columns.values()), axis=1))


def _linear_elements(graph, junction: str) -> list:
    """The I, C and R elements on `junction` (in that order, each in bond order) whose law is
    their own positive value."""
    on = [e for e, _ in junction_elements(graph, junction)
          if e.kind in ("I", "C", "R") and getattr(e, "value", None) is not None and float(e.value.value) > 0]
    return [e for kind in ("I", "C", "R") for e in on if e.kind == kind]


def _quantity(element) -> str:
    """The element's value in words: inertance, resistance, stiffness or compliance."""
    if element.kind == "C":
        return "stiffness" if getattr(element, "stiffness_form", False) else "compliance"
    return {"I": "inertance", "R": "resistance"}[element.kind]
