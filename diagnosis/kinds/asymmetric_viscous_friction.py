"""``asymmetric_viscous_friction`` at a 1-junction: an R whose viscous coefficient depends on the
direction of the flow, :math:`e = b_+ \\max(f, 0) + b_- \\min(f, 0)`.

A car's shock absorber damps its rebound two to three times harder than its compression; a
check valve or a diode passes one way freely and the other hardly; a cylinder's two chambers
drain through different ports.  Viscous friction fitted to such a law takes the mean of the two
coefficients and leaves a residual of one sign in each direction.  Equal coefficients are viscous
friction (:attr:`nests`), which the choice prices lower.  The law is continuous with a kink at rest,
so it needs no smoothing parameter; each coefficient is at least 0 (it dissipates both ways).

It is offered only where the junction's flow goes both ways for at least :data:`BOTH_WAYS` of the
record (the nominal simulation's flow, and the located estimate's for the features): on a flow
that keeps one sign it is viscous friction with a coefficient for the other side that the data
cannot fix, a candidate that predicts as viscous friction does and says more than the record shows.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from .base import Kind, Proposal, register
from .feature_signals import FeatureGroup
from .friction_common import friction_r, namer, viscous


#: the least share of the record the flow must spend on each side of 0
BOTH_WAYS = 0.1


def goes_both_ways(flow) -> bool:
    """Whether `flow` spends at least :data:`BOTH_WAYS` of its samples on each side of 0."""
    flow = np.asarray(flow, dtype=float)
    return flow.size > 0 and min(np.mean(flow > 0), np.mean(flow < 0)) >= BOTH_WAYS


def _flow(values):
    """The junction's flow among its nominal values (the first ``f_<bond>``), or None."""
    return next((v for k, v in values.items() if k.startswith("f_")), None)


@register
class AsymmetricViscousFriction(Kind):
    name = "asymmetric_viscous_friction"
    doors = ("1",)
    feature_doors, feature_names, feature_price = "1", ("max(v, 0)", "min(v, 0)"), 2
    feature_signs = (1, 1)      # a friction takes energy (features.regress_kinds)
    feature_params = 2
    nests = {"viscous_friction": {0: 0, 1: 0}}

    def features(self, s):
        if not goes_both_ways(s.v):
            return []
        columns = np.stack([np.maximum(s.v, 0.0), np.minimum(s.v, 0.0)], axis=1)
        return [FeatureGroup(None, "", list(self.feature_names), columns)]

    def propose(self, site):
        flow = _flow(site.values)
        if flow is not None and not goes_both_ways(flow):
            return []
        coefficient, name = viscous(site), namer(site)
        forward = replace(coefficient, name=name("b_fwd"),
                          description=f"viscous friction coefficient at {site.name} while its flow is positive")
        backward = replace(coefficient, name=name("b_back"),
                           description=f"viscous friction coefficient at {site.name} while its flow is negative")
        # each side alone, at the guess and a tenth and five times it: a missing asymmetry often
        # damps one direction only, where a start on both sides clips the other at its bound 0
        starts = tuple({forward.name: f * g, backward.name: b * g}
                       for g in (0.1 * coefficient.guess, coefficient.guess, 5 * coefficient.guess)
                       for f, b in ((1.0, 0.0), (0.0, 1.0)) if g <= coefficient.upper)
        return [Proposal((forward, backward), starts=starts)]

    def unexcited(self, junction, values):
        """Where the flow keeps one side of 0 (:func:`goes_both_ways`): the other side's
        coefficient is not excited, and a viscous friction is this law on the record."""
        flow = _flow(values)
        if flow is None or goes_both_ways(flow):
            return ""
        flow = np.asarray(flow, dtype=float)
        return (f"the flow at {junction} is positive in {np.mean(flow > 0):.0%} and negative in "
                f"{np.mean(flow < 0):.0%} of the record (a direction-dependent law needs {BOTH_WAYS:.0%} "
                f"on each side)")

    def build(self, graph, cand, values):
        forward, backward = (p.name for p in cand.params)
        return friction_r(graph, cand, f"{forward}*Max(f, 0) + {backward}*Min(f, 0)")

    def explain(self, cand, values, show):
        j = cand.place.name
        forward, backward = (p.name for p in cand.params)
        return (f"the motion at {j} is braked in proportion to its speed, by {show(forward)} while its flow is "
                f"positive and {show(backward)} while it is negative: viscous friction that depends on the "
                f"direction (a damper's compression and rebound, a check valve) at {j}")
