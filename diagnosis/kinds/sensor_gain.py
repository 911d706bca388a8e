"""``sensor_gain`` on an output: the model output ``y`` is read as :math:`g\\, y`."""
from __future__ import annotations

import sympy as sp

from ..catalogue_common import ParamSpec, fresh_name
from .base import Kind, Proposal, register


@register
class SensorGain(Kind):
    name = "sensor_gain"
    doors = ("output",)

    def propose(self, site):
        y = site.name
        return [Proposal((ParamSpec(fresh_name(site.taken, f"gain_{y}"), 1.0, 0.2, 5.0, "1",
                                    f"gain of the {y} sensor"),))]

    def build(self, graph, cand, values):
        return graph.with_output(cand.place.name, lambda y: sp.Symbol(cand.params[0].name) * y)

    def explain(self, cand, values, show):
        y = cand.place.name
        return f"the {y} sensor reads {show(cand.params[0].name)} times the true value: a sensor gain error on output {y}"
