"""``pressure_dependent_friction`` at a 1-junction: an R with
:math:`e = (c_0 + c_1 (P - P_{ref})) \\tanh(f/v_\\varepsilon)`, one candidate per pressure
:math:`P` of the model (a chamber state, a C effort, or their mean;
:func:`~diagnosis.catalogue_scales.pressure_variables`), those among the located regime variables
first (:func:`~diagnosis.catalogue.candidates` orders them).  :math:`P_{ref}` is its mean in the
nominal simulation (fixed), so :math:`c_0` is the Coulomb level at the mean pressure."""
from __future__ import annotations

import numpy as np

from ..catalogue_common import ParamSpec, junction_units
from ..catalogue_scales import pressure_variables
from .base import Kind, register
from .feature_signals import FeatureGroup
from .friction_common import friction_r, level, namer, sharpened, sign, smoothing, with_level_starts


@register
class PressureDependentFriction(Kind):
    name = "pressure_dependent_friction"
    doors = ("1",)
    domains = ("translation", "rotation")
    feature_doors, feature_names, feature_price = "1", ("sign(v)", "(P - P_mean) sign(v)"), 2
    feature_signs = (1,)      # a friction takes energy (features.regress_kinds)
    feature_params, feature_grid_params = 2, (2,)
    nests = {"coulomb_friction": {0: 0, 2: 1}}

    def features(self, s):
        """Sign, and the sign times each moving pressure's deviation from its mean."""
        return sharpened(s, lambda sign: [
            FeatureGroup(expr, "", ["sign(v)", "(P - P_mean) sign(v)"], np.stack([sign, (p - p.mean()) * sign], axis=1))
            for expr, p in s.labelled("pressure").items()])

    def propose(self, site):
        j, E = site.name, site.scales.effort
        e_unit, _ = junction_units(site.graph, j)
        name = namer(site)
        out = []
        for label, expr in pressure_variables(site.graph).items():
            p = site.values.get(f"pressure:{label}")
            p_ref = float(p.mean()) if p is not None else 0.0
            p_scale = float(p.std()) if p is not None and p.std() > 0 else max(abs(p_ref), 1.0)
            out.append(with_level_starts(
                [level(site, "c0", f"Coulomb friction level at {j} at the reference pressure"),
                 ParamSpec(name("c1"), 0.0, -10 * E / p_scale, 10 * E / p_scale, f"{e_unit}/Pa",
                           f"change of the friction level at {j} per Pa of {label}"),
                 smoothing(site)],
                regime=expr,
                constants=((name("p_ref"), p_ref, "Pa", f"reference pressure of the friction law at {j}"),)))
        return out   # those among the located regime variables come first (catalogue.candidates)

    def build(self, graph, cand, values):
        c0, c1 = (p.name for p in cand.params[:2])
        p_ref = cand.constants[0][0]
        return friction_r(graph, cand, f"({c0} + {c1}*(({cand.regime}) - {p_ref}))*{sign(cand)}")

    def explain(self, cand, values, show):
        j = cand.place.name
        c0, c1 = (p.name for p in cand.params[:2])
        slope = values.get(c1, 0.0)
        trend = (f"{'more' if slope > 0 else 'less'} at higher {cand.regime} ({show(c1)})" if slope
                 else f"whatever {cand.regime}")
        p_ref = cand.constants[0][1]
        return (f"the motion at {j} loses about {show(c0)} whenever it moves (at {cand.regime} = "
                f"{p_ref:.4g} Pa), {trend}: pressure-dependent Coulomb friction at the {j} 1-junction")
