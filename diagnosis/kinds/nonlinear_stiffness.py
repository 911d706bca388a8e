"""``nonlinear_stiffness`` of a C at a junction: its law gets a cubic term,
:math:`e = \\Phi(q) + k_3 q^3`, and its own linear value is refitted with it (a linear C's
stiffness or compliance, named as the element; a linear term added to a law): a linear model
identified from data carries the cubic term's average in its linear value.  One candidate per C
on the junction.

The cubic is in the content's departure from its relaxed value, the content at which the C's
effort is the ambient one: 0 for a spring or a gauge pressure, :math:`q_0 = C T_a` for a heat
capacity in absolute temperature (:func:`~diagnosis.catalogue_common.ambient_effort`).  A cubic
about zero content there, 300 K away, is a constant and a linear term over the record's range (a
heat leak's shape, which it had been mistaken for: benchmark seed 4401, case 001), no stiffening."""
from __future__ import annotations

import numpy as np
import sympy as sp

from ..catalogue_common import ParamSpec, ambient_effort, fresh_name, junction_units
from .base import Kind, Proposal, register
from .feature_signals import FeatureGroup
from .storage_common import START_PREFIXES, capacitors, displacement_scale, held_start, held_start_law, units_of


@register
class NonlinearStiffness(Kind):
    name = "nonlinear_stiffness"
    doors = ("1", "0")
    feature_doors, feature_names, feature_price = "1", ("q^3", "q"), 2

    def features(self, s):
        """Per moving C content q: the cubic term and the refitted linear one."""
        return [FeatureGroup(c, "", ["q^3", "q"], np.stack([q ** 3, q], axis=1))
                for c, q in s.labelled("content").items()]

    def feature_start(self, cand, evidence):
        """The cubic coefficient at the coefficient of ``q^3`` and the linear value changed by that
        of ``q`` (the regression's sign convention is the C's: an effort it takes from the
        junction), clipped to their bounds.  A spring's cubic term may be ten thousand times below
        its range's tenth (a pam seesaw's: 0.018 N m/rad^3 against 340), from which the optimiser
        did not leave 0 (seed 3434, case 016)."""
        cubic, linear = (evidence.coefficients.get(name) for name in ("q^3", "q"))
        if cubic is None or not np.isfinite(cubic):
            return None
        k3, own = cand.params
        start = {k3.name: k3.clipped(float(cubic))}
        if linear is not None and np.isfinite(linear):
            value = own.guess + float(linear)          # a stiffness, or a change of one (dk)
            if own.description.startswith("linear compliance"):      # _linear_value's words
                stiffness = 1.0 / own.guess + float(linear)
                value = 1.0 / stiffness if stiffness > 0 else own.guess
            start[own.name] = own.clipped(value)
        return start

    def propose(self, site):
        e_unit, _ = junction_units(site.graph, site.name)
        # the effort a 0-junction's C relaxes towards (its content's zero is elsewhere)
        e_amb = ambient_effort(site.graph, site.name, site.effort) if site.door == "0" else 0.0
        out = []
        for element in capacitors(site):
            c = element.name
            s_unit, q_unit = units_of(element)
            refits_own = element.value is not None and float(element.value.value) > 0     # _linear_value's
            constants = _relaxed_effort(element, site, e_amb, e_unit) + (held_start(site, element) if refits_own else ())
            X = displacement_scale(site, element, _relaxed_content(element, constants, nominal=True))
            k_lin = site.scales.effort / X
            out.append(Proposal(target=c, params=(
                ParamSpec(fresh_name(site.taken, f"k3_{c}"), 0.0, -100 * k_lin / X ** 2, 100 * k_lin / X ** 2,
                          _cubed(e_unit, q_unit) if q_unit else s_unit, f"cubic stiffness coefficient of {c}"),
                _linear_value(element, site.taken, k_lin)),
                constants=constants))
        return out

    def build(self, graph, cand, values):
        """The C's law plus ``k3*q**3``; a linear C keeps its value (refitted under its own name
        by :meth:`Candidate.build <diagnosis.catalogue.Candidate.build>`), a law gets ``dk*q``."""
        c = graph.elements[cand.target]
        k3, linear = (sp.Symbol(spec.name) for spec in cand.params)
        refit_own = c.value is not None and linear.name == c.value.name
        relaxed = _relaxed_content(c, cand.constants)

        def law(old, q):
            own = held_start_law(old, q, cand.constants) if refit_own else old + linear * q
            return own + k3 * (q - relaxed) ** 3
        return graph.with_law(cand.target, law, description=f"{c.description} (with nonlinear stiffness)".strip())

    def explain(self, cand, values, show):
        j = cand.place.name
        k3, linear = cand.params
        cubic = values.get(k3.name, 0.0)
        word = "stiffens" if cubic > 0 else ("softens" if cubic < 0 else "changes its stiffness")
        was = f"{linear.guess:.3g} {linear.unit if linear.unit != '1' else ''}".strip()
        what = f"the spring {cand.target} at {j} {word} with deflection"
        ambient = [c for c in cand.constants if c[0].startswith("e_amb_")]
        if ambient:              # a heat capacity, an absolute pressure's: no spring
            _, e_amb, unit, _ = ambient[0]
            what = f"{cand.target} at {j} {word} away from its content at {e_amb:.5g} {unit}"
        return (f"{what} (cubic term {show(k3.name)}; "
                f"{linear.description.replace(' (refitted)', '')} refitted with it: {show(linear.name)}, "
                f"nominal {was}): nonlinear stiffness of {cand.target}")


def _linear_value(element, taken, k_lin: float) -> ParamSpec:
    """The C's own linear value, refitted with its cubic term: its stiffness (from a hundredth
    of its value to three times it) or compliance (from a third to a hundred times) parameter
    (named as the element) for a linear C, since a linear value identified from data may carry
    most of a strong cubic term's average stiffness; else a linear term
    ``dk_<C> q`` added to its law (within 3 `k_lin` either way).  A zero stiffness (a free mass)
    may become up to 10 `k_lin`, the junction's effort over the C's displacement scale."""
    c = element.name
    if element.value is not None and element.stiffness_form and float(element.value.value) == 0.0:
        return ParamSpec(c, 0.0, 0.0, 10 * k_lin, element.value.unit, f"linear stiffness of {c} (refitted)")
    if element.value is not None and float(element.value.value) > 0:
        v = float(element.value.value)
        quantity = "stiffness" if element.stiffness_form else "compliance"
        low, high = (v / 100, 3 * v) if element.stiffness_form else (v / 3, 100 * v)
        return ParamSpec(c, v, low, high, element.value.unit, f"linear {quantity} of {c} (refitted)")
    return ParamSpec(fresh_name(taken, f"dk_{c}"), 0.0, -3 * k_lin, 3 * k_lin, units_of(element)[0],
                     f"change of the linear stiffness of {c} (refitted)")


def _relaxed_effort(element, site, e_amb: float, e_unit: str) -> tuple:
    """The constant naming the ambient effort a linear C's content relaxes at (none at 0, or for
    a C with a law of its own, whose relaxed content the cubic is not moved to)."""
    if e_amb == 0.0 or element.value is None or not np.isfinite(e_amb):
        return ()
    return ((fresh_name(site.taken, f"e_amb_{element.name}"), float(e_amb), e_unit,
             f"ambient effort at which {element.name}'s content is relaxed"),)


def _relaxed_content(element, constants, nominal: bool = False):
    """The content at which a linear C's effort is the ambient one, in its own (refitted) value
    (sympy; a number at its nominal value with `nominal`): ``e_amb*C`` (``e_amb/k`` in stiffness
    form), or with its start held (:func:`~diagnosis.kinds.storage_common.held_start_law`)
    ``q0 + (e_amb - e0)*C``; 0 without an ambient constant."""
    named = {n.split("_", 1)[0] + "_": (sp.Symbol(n), v) for n, v, *_ in constants}
    if "e_" not in named or element.value is None:
        return 0.0 if nominal else 0
    pick = 1 if nominal else 0
    value = float(element.value.value) if nominal else sp.Symbol(element.value.name)
    q0, e0 = (named[k][pick] if k in named else 0 for k in START_PREFIXES)
    e_amb = named["e_"][pick]
    return q0 + ((e_amb - e0) / value if element.stiffness_form else (e_amb - e0) * value)


def _cubed(e_unit: str, q_unit: str) -> str:
    """The unit of a cubic coefficient: ``N/m^3``, ``Pa/(m^3)^3``."""
    return f"{e_unit}/({q_unit})^3" if "^" in q_unit or "/" in q_unit else f"{e_unit}/{q_unit}^3"
