"""``coulomb_viscous_friction`` at a 1-junction: an R with
:math:`e = F_c \\tanh(f / v_\\varepsilon) + b f`, both levels fitted together as one law (a
lubricated guide or a ball screw has both; fitted one at a time, the first absorbs part of the
second)."""
from __future__ import annotations

import numpy as np

from .base import Kind, register
from .feature_signals import FeatureGroup
from .friction_common import friction_r, level, sign, sharpened, smoothing, viscous, with_level_starts


@register
class CoulombViscousFriction(Kind):
    name = "coulomb_viscous_friction"
    doors = ("1",)
    domains = ("translation", "rotation")
    feature_doors, feature_names, feature_price = "1", ("sign(v)", "v"), 2
    feature_signs = (1, 1)      # a friction takes energy (features.regress_kinds)
    feature_params, feature_grid_params = 2, (2,)
    nests = {"coulomb_friction": {0: 0, 2: 1}, "viscous_friction": {1: 0}}

    def features(self, s):
        return sharpened(s, lambda sign: [FeatureGroup(None, "", ["sign(v)", "v"], np.stack([sign, s.v], axis=1))])

    def propose(self, site):
        return [with_level_starts([level(site, "Fc", f"Coulomb friction level at {site.name}"), viscous(site),
                                   smoothing(site)])]

    def build(self, graph, cand, values):
        fc, b = (p.name for p in cand.params[:2])
        return friction_r(graph, cand, f"{fc}*{sign(cand)} + {b}*f")

    def explain(self, cand, values, show):
        j = cand.place.name
        fc, b = (p.name for p in cand.params[:2])
        return (f"the motion at {j} loses about {show(fc)} whenever it moves plus {show(b)} times its "
                f"speed: Coulomb and viscous friction together at the {j} 1-junction")
