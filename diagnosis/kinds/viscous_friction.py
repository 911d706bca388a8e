"""``viscous_friction`` at a 1-junction: an R with :math:`e = b f`."""
from __future__ import annotations

from ..catalogue_common import unit_domain
from .base import Kind, register
from .feature_signals import FeatureGroup
from .friction_common import friction_r, viscous, with_level_starts


@register
class ViscousFriction(Kind):
    name = "viscous_friction"
    doors = ("1",)
    feature_doors, feature_names, feature_price = "1", ("v",), 1
    feature_signs = (1,)      # a friction takes energy (features.regress_kinds)
    feature_params = 1

    def features(self, s):
        return [FeatureGroup(None, "", ["v"], s.v[:, None])]

    def propose(self, site):
        return [with_level_starts([viscous(site)])]

    def build(self, graph, cand, values):
        return friction_r(graph, cand, f"{cand.params[0].name}*f")

    def explain(self, cand, values, show):
        j, b = cand.place.name, cand.params[0].name
        other = _NOT_MOTION.get(unit_domain(cand.params[0].unit, "resistance"))
        if other:           # the same law outside mechanics: a resistance the model leaves out
            return f"{other} at {j}: an effort in proportion to its flow ({show(b)}): viscous friction at {j}"
        return f"the motion at {j} is braked in proportion to its speed ({show(b)}): viscous friction at {j}"


#: the linear resistance in the words of the domains that are not mechanics
_NOT_MOTION = {"electrical": "a series resistance the model leaves out",
               "hydraulic": "a flow resistance the model leaves out",
               "pneumatic": "a flow resistance the model leaves out",
               "thermal": "a thermal resistance the model leaves out"}
