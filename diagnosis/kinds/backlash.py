"""``backlash`` in front of a C at a 1-junction: the C's law acts on the displacement beyond a
play of :math:`\\pm b`, :math:`e = \\Phi(q - \\mathrm{clip}(q, -b, b))` (a compliant transmission
with a dead zone of total width 2b).  One candidate per C on the junction."""
from __future__ import annotations

import sympy as sp

from ..catalogue_common import ParamSpec, fresh_name
from .base import Kind, Proposal, register
from .storage_common import capacitors, displacement_scale, units_of


@register
class Backlash(Kind):
    name = "backlash"
    doors = ("1",)

    def propose(self, site):
        out = []
        for element in capacitors(site):
            c, X = element.name, displacement_scale(site, element)
            out.append(Proposal(target=c, params=(
                ParamSpec(fresh_name(site.taken, f"b_play_{c}"), 0.1 * X, 0.0, 3 * X, units_of(element)[1],
                          f"half-width of the play in front of {c}"),)))
        return out

    def build(self, graph, cand, values):
        c = graph.elements[cand.target]
        b = sp.Symbol(cand.params[0].name)
        return graph.with_law(cand.target, lambda old, q: old.xreplace({q: q - sp.Max(-b, sp.Min(b, q))}),
                              description=f"{c.description} (with backlash)".strip())

    def explain(self, cand, values, show):
        return (f"the spring {cand.target} at {cand.place.name} only engages beyond a play of "
                f"+/- {show(cand.params[0].name)}: backlash in front of {cand.target}")
