"""``sensor_offset`` on an output: the model output ``y`` is read as :math:`y + \\delta`."""
from __future__ import annotations

import numpy as np
import sympy as sp

from ..catalogue_common import ParamSpec, fresh_name
from .base import Kind, Proposal, register


@register
class SensorOffset(Kind):
    name = "sensor_offset"
    doors = ("output",)

    def propose(self, site):
        y, measured = site.name, site.recorded
        width = float(np.ptp(measured)) if measured is not None and np.ptp(measured) > 0 else 1.0
        return [Proposal((ParamSpec(fresh_name(site.taken, f"offset_{y}"), 0.0, -2 * width, 2 * width,
                                    site.graph.outputs[y].unit, f"offset of the {y} sensor"),))]

    def build(self, graph, cand, values):
        return graph.with_output(cand.place.name, lambda y: y + sp.Symbol(cand.params[0].name))

    def explain(self, cand, values, show):
        y = cand.place.name
        return f"the {y} sensor reads {show(cand.params[0].name)} off: a sensor offset on output {y}"
