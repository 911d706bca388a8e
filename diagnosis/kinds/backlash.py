"""``backlash`` in front of a C at a 1-junction: the C's law acts on the displacement beyond a
play of :math:`\\pm b`, :math:`e = \\Phi(q - \\mathrm{clip}(q, -b, b))` (a compliant transmission
with a dead zone of total width 2b).  One candidate per C on the junction."""
from __future__ import annotations

import numpy as np
import sympy as sp

from ..catalogue_common import ParamSpec, fresh_name
from .base import Kind, Proposal, register
from .feature_signals import FeatureGroup, rms
from .storage_common import capacitors, carries_effort, displacement_scale, units_of


#: the half-widths of the play the features try, as fractions of the C content's RMS
FEATURE_GRID = (0.1, 0.3, 1.0)


@register
class Backlash(Kind):
    name = "backlash"
    doors = ("1",)
    domains = ("translation", "rotation")
    feature_doors, feature_names, feature_price = "1", ("clip(q, -b, b)",), 1

    def features(self, s):
        """Per moving C content q of a C whose law carries an effort: the part inside a play of
        half-width b on a grid of its RMS.  A play in front of a C that carries nothing (a
        carriage's zero-stiffness position meter) changes nothing; its column, a force of the
        clipped position with a free coefficient, would stand in for other physics."""
        carrying = s.labelled("c_effort")
        return [FeatureGroup(c, f"b = {f * rms(q):.3g}", ["clip(q, -b, b)"],
                             np.clip(q, -f * rms(q), f * rms(q))[:, None])
                for c, q in s.labelled("content").items() if c in carrying for f in FEATURE_GRID]

    def propose(self, site):
        out = []
        for element in capacitors(site):
            if not carries_effort(element):
                continue            # a play in front of a law that is zero changes nothing
            c, X = element.name, displacement_scale(site, element)
            b = fresh_name(site.taken, f"b_play_{c}")
            # the cost is flat where the play is too small to act and kinked where it engages:
            # starts over two decades of the displacement scale
            out.append(Proposal(target=c, params=(
                ParamSpec(b, 0.1 * X, 0.0, 3 * X, units_of(element)[1], f"half-width of the play in front of {c}"),),
                starts=tuple({b: f * X} for f in (0.03, 0.3, 1.0))))
        return out

    def build(self, graph, cand, values):
        c = graph.elements[cand.target]
        b = sp.Symbol(cand.params[0].name)
        return graph.with_law(cand.target, lambda old, q: old.xreplace({q: q - sp.Max(-b, sp.Min(b, q))}),
                              description=f"{c.description} (with backlash)".strip())

    def explain(self, cand, values, show):
        return (f"the spring {cand.target} at {cand.place.name} only engages beyond a play of "
                f"+/- {show(cand.params[0].name)}: backlash in front of {cand.target}")
