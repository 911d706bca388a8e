"""``leak`` at a 0-junction: an R from the junction (common effort ``e``: a pressure, a temperature)
to the ambient, :math:`f = c_{leak} (e - e_{amb})`; for pneumatic pseudo-bonds a mass flow
proportional to the pressure difference, for a thermal junction a heat flow to the room.
:math:`e_{amb}` is fixed (:func:`~diagnosis.catalogue_common.ambient_effort`): 101325 Pa for a
pneumatic junction whose mean pressure exceeds 50 kPa (absolute pressures), the ambient
temperature the model names for a thermal one, else 0 (gauge pressures, other domains)."""
from __future__ import annotations

import numpy as np

from bondgraph import R
from bondgraph.params import DOMAINS

from ..catalogue_common import (ParamSpec, ambient_effort, fresh_name, junction_domain, junction_units,
                                pneumatic_ambient)
from .base import Kind, Proposal, hang, register
from .feature_signals import FeatureGroup


@register
class Leak(Kind):
    name = "leak"
    doors = ("0",)
    feature_doors, feature_names, feature_price = "0", ("e - P_amb",), 1
    feature_signs = (1,)      # a loss takes energy (features.regress_kinds)
    feature_params = 1

    def features(self, s):
        e = np.asarray(s.values["effort"], float)
        if s.ambient is not None:
            p_amb = s.ambient
        else:
            p_amb = pneumatic_ambient(e) if s.domain == "pneumatic" else 0.0
        return [FeatureGroup(None, "", ["e - P_amb"], (e - p_amb)[:, None])]

    def propose(self, site):
        j, graph = site.name, site.graph
        e_unit, f_unit = junction_units(graph, j)
        e = site.effort
        e_mean = float(e.mean()) if e is not None else 0.0
        p_amb = ambient_effort(graph, j, e)
        dev, F = max(abs(e_mean - p_amb), site.scales.effort), site.scales.flow
        c = fresh_name(site.taken, f"c_leak_{j}")
        # a leak's flow may be any fraction of the junction's flows: starts over five decades
        return [Proposal(
            (ParamSpec(c, 0.1 * F / dev, 0.0, 100 * F / dev,
                       f"({f_unit})/({e_unit})" if e_unit else "", f"leak conductance at {j}"),),
            constants=((fresh_name(site.taken, f"P_amb_{j}"), p_amb, e_unit,
                        f"ambient pressure the leak at {j} vents to"),),
            starts=tuple({c: k * F / dev} for k in (1e-5, 1e-4, 1e-3, 1e-2)))]

    def build(self, graph, cand, values):
        j = cand.place.name
        return hang(graph, R(f"leak_{j}", flow=f"{cand.params[0].name}*(e - {cand.constants[0][0]})",
                             domain=junction_domain(graph, j), description=f"leak from {j} to the ambient"), j)

    def explain(self, cand, values, show):
        j = cand.place.name
        _, ambient, unit, _ = cand.constants[0]
        if unit == DOMAINS["thermal"].effort:
            return (f"{j} loses {show(cand.params[0].name)} of heat flow per kelvin above the ambient "
                    f"{ambient:.5g} {unit}: a heat leak at {j}")
        return (f"the chamber at {j} loses {show(cand.params[0].name)} of flow per unit of pressure above "
                f"ambient: a leak at {j}")
