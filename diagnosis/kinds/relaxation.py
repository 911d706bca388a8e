"""``relaxation`` at a 1-junction: a resistance and a storage in parallel, in series with the
junction's other elements, that the model leaves out.

A 0-junction hung on the 1-junction carries an R (:math:`f_R = e / R_r`) and a C
(:math:`e = q / C_r`, starting discharged), so the effort it takes from the junction follows the
junction's flow :math:`f` through a first-order lag,

.. math::

    \\tau_r \\dot e = R_r f - e, \\qquad \\tau_r = R_r C_r:

an extra resistance :math:`R_r` to slow changes whose effort builds up over :math:`\\tau_r`.  Where
it lives: a battery cell's polarisation (the RC pair of a Thevenin model, Plett, *Battery
Management Systems* vol. 1, 2015, sec. 2.7), a viscoelastic mount or a belt (a Maxwell element:
damper :math:`R_r` in series with a spring :math:`1/C_r`, to the ground), an electrolytic
capacitor's dielectric absorption.  It is the dual of ``heat_transfer`` at a 0-junction (a storage
reached through a resistance) and, as :math:`\\tau_r \\to 0`, the viscous friction :math:`R_r f`.
Fitted: :math:`R_r` and :math:`\\tau_r`.  The feature: the junction's flow through a lag of each
trial time constant (:data:`FEATURE_LAG_STEPS`), started at 0 as the branch is.
"""
from __future__ import annotations

from bondgraph import C, R, Zero
from bondgraph.params import DOMAINS

from ..catalogue_common import ParamSpec, junction_domain, unit_domain
from .base import Kind, Proposal, hang, register
from .feature_signals import FeatureGroup, lagged
from .friction_common import namer, viscous

#: the time constants the features try and the fit starts from, in sample intervals (each four
#: times the last; those under a quarter of the record)
FEATURE_LAG_STEPS = (2.0, 8.0, 32.0, 128.0, 512.0)


def _taus(dt: float, span: float) -> list[float]:
    return [n * dt for n in FEATURE_LAG_STEPS if n * dt < span / 4] or [dt]


@register
class Relaxation(Kind):
    name = "relaxation"
    doors = ("1",)
    domains = ("electrical", "translation", "rotation", "hydraulic")
    feature_doors, feature_names, feature_price = "1", ("lag(v)",), 2
    feature_signs = (1,)      # a damping takes energy (features.regress_kinds)
    feature_params, feature_grid_params = 1, (1,)

    def features(self, s):
        """The flow through a lag of each trial time constant, from 0 as the branch starts."""
        return [FeatureGroup(None, f"tau {tau:.3g} s", ["lag(v)"], lagged(s.v, s.t, tau, start=0.0)[:, None],
                             (float(tau),)) for tau in _taus(s.dt, s.span)]

    def propose(self, site):
        scales = site.scales
        damping = viscous(site)                 # its scale and unit: the branch settles to one
        tau = namer(site)("tau_relax")
        taus = _taus(scales.dt, scales.span)
        resistance = ParamSpec(namer(site)("R_relax"), damping.guess, 0.0, damping.upper, damping.unit,
                               f"resistance of the relaxing branch at {site.name} (its effort per flow, settled)")
        return [Proposal((resistance, ParamSpec(tau, taus[len(taus) // 2], scales.dt / 2, scales.span / 2, "s",
                                                f"time constant of the relaxing branch at {site.name}")),
                         starts=tuple({tau: t} for t in taus))]

    def build(self, graph, cand, values):
        j = cand.place.name
        r, tau = (spec.name for spec in cand.params)
        dom = junction_domain(graph, j)
        branch = f"relax_{j}"
        graph = hang(graph, Zero(branch, description=f"relaxing branch at {j}: a resistance and a storage in parallel"),
                     j)
        # the R's flow e/R_r; the C's effort q/C_r = q R_r/tau_r, its charge starting at 0
        graph = hang(graph, R(f"R_relax_el_{j}", flow=f"e/Max({r}, 1e-300)", domain=dom,
                              description=f"resistance of the relaxing branch at {j}"), branch)
        return hang(graph, C(f"C_relax_el_{j}", law=f"q*{r}/{tau}", domain=dom, state=f"q_relax_{j}", initial=0.0,
                             description=f"storage of the relaxing branch at {j} (capacity tau/R)"), branch)

    def explain(self, cand, values, show):
        j = cand.place.name
        r, tau = (spec.name for spec in cand.params)
        dom = unit_domain(cand.params[0].unit, "resistance")
        pair = ""
        if values.get(r, 0.0) > 0:
            pair = f", {values[tau] / values[r]:.3g} {DOMAINS[dom].compliance if dom else ''}".rstrip()
        words = {"electrical": "the voltage across an RC pair the model leaves out (a cell's polarisation)",
                 "translation": "a spring and damper in series to the ground (a Maxwell element: a mount, a belt)",
                 "rotation": "a torsional spring and damper in series to the ground (a Maxwell element)"}
        what = words.get(dom, "a resistance and a storage in parallel that the model leaves out")
        return (f"a share of the effort at {j} follows its flow with a lag of {show(tau)}, settling at {show(r)} "
                f"times the flow: {what} ({show(r)}{pair}): relaxation at {j}")
