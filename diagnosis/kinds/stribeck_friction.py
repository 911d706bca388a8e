"""``stribeck_friction`` at a 1-junction: an R with
:math:`e = (F_c + \\Delta F_s e^{-(f/v_s)^2}) \\tanh(f/v_\\varepsilon)` (static level
:math:`F_c + \\Delta F_s`; viscous friction is its own kind)."""
from __future__ import annotations

from ..catalogue_common import ParamSpec, junction_units
from .base import Kind, register
from .friction_common import friction_r, level, namer, sign, smoothing_flow, with_level_starts


@register
class StribeckFriction(Kind):
    name = "stribeck_friction"
    doors = ("1",)

    def propose(self, site):
        j, V = site.name, site.scales.flow
        _, f_unit = junction_units(site.graph, j)
        return [with_level_starts([
            level(site, "Fc", f"Coulomb friction level at {j}"),
            level(site, "dFs", f"static friction in excess of the Coulomb level at {j}"),
            ParamSpec(namer(site)("v_s"), 0.2 * V, 0.005 * V, 10 * V, f_unit, f"Stribeck velocity at {j}")],
            constants=(smoothing_flow(site),))]

    def build(self, graph, cand, values):
        fc, dfs, vs = (p.name for p in cand.params)
        return friction_r(graph, cand, f"({fc} + {dfs}*exp(-(f/{vs})**2))*{sign(cand)}")

    def explain(self, cand, values, show):
        j = cand.place.name
        fc, dfs, vs = (p.name for p in cand.params)
        return (f"the motion at {j} loses {show(fc)} when sliding and up to {show(dfs)} more near "
                f"standstill (fading above about {show(vs)}): Stribeck friction at {j}")
