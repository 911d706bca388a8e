"""``quadratic_drag`` at a 1-junction: an R with :math:`e = c_d f |f|`.

Drag that grows with the square of the speed: a fan or a propeller, a body moving through air or
water, turbulent flow through a pipe or a valve.  Fitted as viscous friction, it takes the mean
slope over the record's speeds and leaves too little at high speed and too much at low speed.  The
coefficient is at least 0 (it dissipates), and the law is smooth enough for the integrators (its
slope is 0 at rest).
"""
from __future__ import annotations

import numpy as np

from ..catalogue_common import ParamSpec, junction_units
from .base import Kind, Proposal, register
from .feature_signals import FeatureGroup
from .friction_common import friction_r, namer


@register
class QuadraticDrag(Kind):
    name = "quadratic_drag"
    doors = ("1",)
    domains = ("translation", "rotation", "hydraulic", "pneumatic")
    feature_doors, feature_names, feature_price = "1", ("v |v|",), 1
    feature_signs = (1,)      # a friction takes energy (features.regress_kinds)
    feature_params = 1

    def features(self, s):
        return [FeatureGroup(None, "", ["v |v|"], (s.v * np.abs(s.v))[:, None])]

    def propose(self, site):
        e_unit, f_unit = junction_units(site.graph, site.name)
        E, V = site.scales.effort, site.scales.flow
        unit = f"{e_unit}/({f_unit})^2" if f_unit else ""
        c_d = ParamSpec(namer(site)("c_d"), 0.1 * E / V ** 2, 0.0, 100 * E / V ** 2, unit,
                        f"quadratic drag coefficient at {site.name}")
        return [Proposal((c_d,), starts=tuple({c_d.name: f * c_d.guess} for f in (0.1, 5.0)))]

    def build(self, graph, cand, values):
        return friction_r(graph, cand, f"{cand.params[0].name}*f*Abs(f)")

    def explain(self, cand, values, show):
        j = cand.place.name
        return (f"the motion at {j} meets a drag of {show(cand.params[0].name)} times its speed squared, "
                f"against the motion (a fan, a fluid's drag, turbulent flow): quadratic drag at {j}")
