"""``stribeck_friction`` at a 1-junction: an R with
:math:`e = (F_c + \\Delta F_s e^{-(f/v_s)^2}) \\tanh(f/v_\\varepsilon)` (static level
:math:`F_c + \\Delta F_s`; viscous friction is its own kind)."""
from __future__ import annotations

import numpy as np

from ..catalogue_common import ParamSpec, junction_units
from .base import Kind, register
from .feature_signals import FeatureGroup
from .friction_common import (SHARPNESS_GRID, V_EPS_FRACTION, friction_r, level, namer, sharpened, sign, smoothing,
                              with_level_starts)


#: the Stribeck velocities the features try, as fractions of the RMS flow
FEATURE_GRID = (0.1, 0.3, 1.0)
#: from a Coulomb fit's level: the peaks (fractions of the level), decay velocities and smoothing
#: flows (fractions of the RMS flow) a Stribeck fit also starts at (:meth:`StribeckFriction.starts_from`)
PEAKS, DECAYS, SIGNS = (0.5, 1.0, 2.0), FEATURE_GRID[:2], SHARPNESS_GRID[:2]


@register
class StribeckFriction(Kind):
    name = "stribeck_friction"
    doors = ("1",)
    domains = ("translation", "rotation")
    feature_doors, feature_names, feature_price = "1", ("sign(v)", "exp(-(v/v_s)^2) sign(v)"), 3
    feature_signs = (1, 1)      # a friction takes energy (features.regress_kinds)
    feature_params, feature_grid_params = 2, (2, 3)    # Fc, dFs from the coefficients; v_s, v_eps from the grid
    nests = {"coulomb_friction": {0: 0, 3: 1}}

    def features(self, s):
        """Sign and Stribeck decay, the decay velocity on a grid of the RMS flow."""
        return sharpened(s, lambda sign: [
            FeatureGroup(None, f"v_s = {f * s.v_rms:.3g}", ["sign(v)", "exp(-(v/v_s)^2) sign(v)"],
                         np.stack([sign, np.exp(-(s.v / (f * s.v_rms)) ** 2) * sign], axis=1), (float(f * s.v_rms),))
            for f in FEATURE_GRID])

    def propose(self, site):
        j, V = site.name, site.scales.flow
        _, f_unit = junction_units(site.graph, j)
        return [with_level_starts([
            level(site, "Fc", f"Coulomb friction level at {j}"),
            level(site, "dFs", f"static friction in excess of the Coulomb level at {j}"),
            ParamSpec(namer(site)("v_s"), 0.2 * V, 0.005 * V, 10 * V, f_unit, f"Stribeck velocity at {j}"),
            smoothing(site)])]

    def starts_from(self, cand, simpler, values):
        """Besides the Coulomb fit's level with no peak, that level with a peak of half, once and
        twice it, decaying at a tenth and three tenths of the RMS flow, under a sign as sharp as the
        features' sharpest two (:data:`PEAKS`, :data:`DECAYS`, :data:`SIGNS`).  At no peak the
        decay velocity has no gradient, and a peak's stick and slip make the training error rugged
        in it: from the Coulomb fit alone, the pam seesaw's Stribeck friction stayed a Coulomb
        friction smoothed over 14 % of the speed (seed 1212, case 034)."""
        starts = super().starts_from(cand, simpler, values)
        if not starts:
            return starts
        fc, dfs, vs, eps = cand.params
        coulomb = starts[0][fc.name]
        flow = eps.guess / V_EPS_FRACTION
        return starts + [{fc.name: coulomb, dfs.name: dfs.clipped(a * coulomb), vs.name: vs.clipped(b * flow),
                          eps.name: eps.clipped(e * flow)} for a in PEAKS for b in DECAYS for e in SIGNS]

    def build(self, graph, cand, values):
        fc, dfs, vs = (p.name for p in cand.params[:3])
        return friction_r(graph, cand, f"({fc} + {dfs}*exp(-(f/{vs})**2))*{sign(cand)}")

    def explain(self, cand, values, show):
        j = cand.place.name
        fc, dfs, vs = (p.name for p in cand.params[:3])
        return (f"the motion at {j} loses {show(fc)} when sliding and up to {show(dfs)} more near "
                f"standstill (fading above about {show(vs)}): Stribeck friction at {j}")
