"""``hysteresis`` at a 1-junction: Dahl friction [1]_, an equation element with the friction
effort :math:`z` as state, :math:`\\dot z = \\sigma (f - |f| z / F_h)`: elastic (stiffness
:math:`\\sigma`) for small reversals, :math:`\\pm F_h` in steady sliding, rate-independent
hysteresis loops in between.  Also electrical: a battery cell's open-circuit-voltage hysteresis
in Plett's one-state form [2]_, :math:`\\dot h = |\\eta i \\gamma / Q| (\\mathrm{sgn}(i) - h)`
with :math:`M h` added to the voltage, is this law in the charge (:math:`F_h = M`,
:math:`\\sigma = \\eta \\gamma M / Q`).

References
----------
.. [1] P. R. Dahl, "Solid friction damping of mechanical vibrations", AIAA Journal 14(12), 1976,
   eq. (1) with exponent 1.
.. [2] G. L. Plett, "Extended Kalman filtering for battery management systems of LiPB-based HEV
   battery packs, Part 2", J. Power Sources 134(2), 2004, sec. 3.4 (one-state hysteresis).
"""
from __future__ import annotations

import numpy as np

from bondgraph import EquationElement

from ..catalogue_common import ParamSpec, junction_units, unit_domain
from .base import Kind, hang, register
from .feature_signals import FeatureGroup, dahl_state, rms
from .friction_common import displacement_unit, namer, with_level_starts


#: the Dahl stiffness over level sigma/F_h the features try, times the RMS displacement
FEATURE_GRID = (1.0, 3.0, 10.0, 30.0, 100.0)


@register
class Hysteresis(Kind):
    name = "hysteresis"
    doors = ("1",)
    domains = ("translation", "rotation", "electrical")
    feature_doors, feature_names, feature_price = "1", ("z_dahl",), 2
    feature_signs = (1,)      # a friction takes energy (features.regress_kinds)

    def features(self, s):
        """The Dahl state for sigma/F_h on a grid of the RMS displacement."""
        X = rms(s.displacement)
        return [FeatureGroup(None, f"sigma/F_h = {a / X:.3g}", ["z_dahl"],
                             dahl_state(s.v, s.t, a / X, s.travel)[:, None], grid=(a / X,))
                for a in FEATURE_GRID]

    def feature_start(self, cand, evidence):
        """The level at the coefficient of the normalised Dahl state (the Dahl friction is
        :math:`F_h z`), the stiffness at the grid's :math:`\\sigma / F_h` times it: a friction far
        below the place's effort scale (a muscle's braid on a light joint, a thousandth of a
        percent of its force) is out of reach of the optimiser from a tenth of that scale."""
        coef = evidence.coefficients.get("z_dahl")
        if coef is None or not np.isfinite(coef) or coef <= 0 or len(evidence.grid) != 1:
            return None
        fh, sigma = cand.params
        level = fh.clipped(float(coef))
        return {fh.name: level, sigma.name: sigma.clipped(float(evidence.grid[0]) * level)}

    def propose(self, site):
        j, E, X = site.name, site.scales.effort, site.scales.displacement
        e_unit, f_unit = junction_units(site.graph, j)
        name = namer(site)
        return [with_level_starts([
            # the level down to a millionth of the effort scale, which may be far above the friction
            # (a cylinder's p A, a muscle's force on a light joint)
            ParamSpec(name("Fh"), 0.1 * E, 1e-6 * E, 10 * E, e_unit, f"Dahl friction level at {j}"),
            # the stiffness down to a thousandth of the level guess over one RMS displacement (a
            # seal's loop may close only over most of a stroke), and as far below as the level
            ParamSpec(name("sigma_dahl"), 2.0 * E / X, 1e-7 * E / X, 2e3 * E / X,
                      f"{e_unit}/{displacement_unit(f_unit)}", f"Dahl pre-sliding stiffness at {j}")])]

    def build(self, graph, cand, values):
        j = cand.place.name
        fh, sigma = (p.name for p in cand.params)
        state = f"F_dahl_{j}"
        element = EquationElement(f"hysteresis_{j}", ports={"m": "in"}, outputs={"e_m": state},
                                  states={state: f"{sigma}*(f_m - Abs(f_m)*{state}/{fh})"}, initial={state: 0.0},
                                  units={state: junction_units(graph, j)[0]},
                                  description=f"Dahl hysteretic friction at {j}")
        return hang(graph, element, j)

    def explain(self, cand, values, show):
        j = cand.place.name
        fh, sigma = (p.name for p in cand.params)
        if unit_domain(cand.params[0].unit, "effort") == "electrical":     # a cell's voltage hysteresis, in charge
            span = values.get(fh, 0.0) / values[sigma] if values.get(sigma, 0.0) > 0 else float("nan")
            return (f"the voltage at {j} carries a hysteresis of up to +-{show(fh)} that turns over with the "
                    f"current's direction within about {span:.3g} C of charge ({show(sigma)}): a voltage "
                    f"hysteresis (Plett's one-state model, a Dahl law in the charge) at {j}")
        return (f"the motion at {j} meets a friction of up to {show(fh)} that builds up elastically "
                f"({show(sigma)}) after each reversal: hysteretic (Dahl) friction at {j}")
