"""``radiation`` at a thermal 0-junction: heat radiated to the surroundings by the Stefan-Boltzmann
law, :math:`f = c_{rad} (T^4 - T_{amb}^4)` with :math:`c_{rad} = \\varepsilon \\sigma A` (W/K^4),
an R hung on the junction.

A linear convective loss, refitted, takes the radiation's slope at the working temperature, and a
sensor offset its curvature (a heater block's radiation was answered so, twice the noise floor
left); the fourth power says which law the loss follows.  Offered where the junction's temperatures
are absolute (a mean above :data:`ABSOLUTE` K: the fourth power of a temperature rise is no law);
the surroundings are at the ambient the model names (:func:`~diagnosis.catalogue_common.ambient_effort`).
"""
from __future__ import annotations

import numpy as np

from bondgraph import R

from ..catalogue_common import ParamSpec, ambient_effort, fresh_name
from .base import Kind, Proposal, hang, register
from .feature_signals import FeatureGroup

#: the Stefan-Boltzmann constant, W/(m^2 K^4)
SIGMA = 5.670374419e-8
#: a junction's mean temperature above which its temperatures are taken as absolute, K
ABSOLUTE = 100.0


@register
class Radiation(Kind):
    name = "radiation"
    doors = ("0",)
    domains = ("thermal",)
    feature_doors, feature_names, feature_price = "0", ("T^4 - T_amb^4",), 1
    feature_signs = (1,)      # a loss takes energy (features.regress_kinds)
    feature_params = 1

    def features(self, s):
        T = np.asarray(s.values["effort"], float)
        if s.domain != "thermal" or not float(np.mean(T)) > ABSOLUTE:
            return []
        ambient = s.ambient if s.ambient is not None else float(T[0])
        return [FeatureGroup(None, "", ["T^4 - T_amb^4"], (T ** 4 - ambient ** 4)[:, None])]

    def propose(self, site):
        graph, j = site.graph, site.name
        T = site.effort
        ambient = ambient_effort(graph, j, T)
        # without data the ambient the model names tells whether its temperatures are absolute
        if not (float(np.mean(T)) if T is not None else ambient) > ABSOLUTE:
            return []
        # the radiated flow's typical size per unit of c_rad: its spread about the ambient's
        spread = float(np.sqrt(np.mean((np.asarray(T) ** 4 - ambient ** 4) ** 2))) if T is not None else 0.0
        dev = max(spread, 4.0 * ambient ** 3 * site.scales.effort)
        F = site.scales.flow
        c = fresh_name(site.taken, f"c_rad_{j}")
        return [Proposal(
            (ParamSpec(c, 0.1 * F / dev, 0.0, 100 * F / dev, "W/K^4",
                       f"emissivity x area x Stefan-Boltzmann constant at {j}"),),
            constants=((fresh_name(site.taken, f"T_amb_{j}"), ambient, "K",
                        f"temperature of the surroundings {j} radiates to"),),
            starts=tuple({c: k * F / dev} for k in (1e-3, 1e-2, 1.0)))]

    def build(self, graph, cand, values):
        j = cand.place.name
        c, ambient = cand.params[0].name, cand.constants[0][0]
        return hang(graph, R(f"radiation_{j}", flow=f"{c}*(e**4 - {ambient}**4)", domain="thermal",
                             description=f"thermal radiation from {j} to its surroundings"), j)

    def explain(self, cand, values, show):
        j = cand.place.name
        _, ambient, unit, _ = cand.constants[0]
        eps_area = values[cand.params[0].name] / SIGMA
        return (f"{j} radiates heat to surroundings at {ambient:.5g} {unit}, {show(cand.params[0].name)} times "
                f"T^4 - T_amb^4 (an emissivity-area product of {eps_area:.3g} m^2): thermal radiation at {j}")
