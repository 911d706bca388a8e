"""``coulomb_friction`` at a 1-junction: an R with :math:`e = F_c \\tanh(f / v_\\varepsilon)`
(:mod:`~diagnosis.kinds.friction_common` for the smoothing flow)."""
from __future__ import annotations

from .base import Kind, register
from .feature_signals import FeatureGroup
from .friction_common import friction_r, level, sign, sharpened, smoothing, with_level_starts


@register
class CoulombFriction(Kind):
    name = "coulomb_friction"
    doors = ("1",)
    domains = ("translation", "rotation", "electrical")
    feature_doors, feature_names, feature_price = "1", ("sign(v)",), 1
    feature_signs = (1,)      # a friction takes energy (features.regress_kinds)
    feature_params, feature_grid_params = 1, (1,)

    def features(self, s):
        return sharpened(s, lambda sign: [FeatureGroup(None, "", ["sign(v)"], sign[:, None])])

    def propose(self, site):
        return [with_level_starts([level(site, "Fc", f"Coulomb friction level at {site.name}"),
                                   smoothing(site)])]

    def build(self, graph, cand, values):
        return friction_r(graph, cand, f"{cand.params[0].name}*{sign(cand)}")

    def explain(self, cand, values, show):
        j = cand.place.name
        return (f"the motion at {j} loses about {show(cand.params[0].name)} whenever it moves, whatever its "
                f"speed: Coulomb friction at the {j} 1-junction")
