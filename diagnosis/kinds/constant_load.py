"""``constant_load`` at a junction: a force offset, a gravity-like load on a lifted axis, a
preload, a pump's constant bypass flow.

An effort that does not depend on the motion (at a 1-junction) or a flow that does not depend on
the pressure (at a 0-junction), built as an R whose law is a constant (``e = F_0`` in resistance
causality at a 1-junction, ``f = Q_0`` in conductance causality at a 0-junction), so it saves,
derives and exports like any element; with the power convention of an R the load *takes*
``F_0 v`` (``Q_0 e``) from the junction, and either sign is fitted.
"""
from __future__ import annotations

import numpy as np

from bondgraph import R

from ..catalogue_common import ParamSpec, fresh_name, junction_domain, junction_units
from .base import Kind, Proposal, hang, register
from .feature_signals import FeatureGroup


@register
class ConstantLoad(Kind):
    name = "constant_load"
    doors = ("1", "0")
    feature_doors, feature_names, feature_price = "01", ("1",), 1
    feature_params = 1

    def features(self, s):
        return [FeatureGroup(None, "", ["1"], np.ones((s.t.size, 1)))]

    def propose(self, site):
        j = site.name
        e_unit, f_unit = junction_units(site.graph, j)
        one = site.door == "1"
        size, unit = (site.scales.effort, e_unit) if one else (site.scales.flow, f_unit)
        spec = ParamSpec(fresh_name(site.taken, f"{'F0' if one else 'Q0'}_{j}"), 0.0, -10 * size, 10 * size, unit,
                         f"constant {'effort' if one else 'flow'} taken from {j}")
        return [Proposal((spec,), starts=tuple({spec.name: s * 0.1 * size} for s in (1.0, -1.0)))]

    def build(self, graph, cand, values):
        j, p = cand.place.name, cand.params[0].name
        law = {"effort": p} if graph.elements[j].kind == "1" else {"flow": p}
        return hang(graph, R(f"constant_load_{j}", domain=junction_domain(graph, j), **law,
                             description=f"constant load at {j}"), j)

    def explain(self, cand, values, show):
        j, p = cand.place.name, cand.params[0].name
        what = "effort" if p.startswith("F0") else "flow"
        return (f"a constant {what} of {show(p)} is taken from {j} whatever the motion (an offset, a preload or "
                f"a gravity-like load): a constant load at {j}")
