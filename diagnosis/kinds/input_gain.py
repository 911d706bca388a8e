"""``input_gain`` on an input: the plant receives :math:`u_0 + g\\,(u - u_0)` where the recording
says :math:`u` (an actuator's gain off its data sheet's, a motor's torque constant, a current
sensor's scale).

The gain scales the input's departures from where it rests, :math:`u_0`
(:func:`~diagnosis.kinds.signal_common.resting_input`, usually 0: a force, a voltage; a
proportional valve closed at 5 V): the plant at rest stays at rest.  On a linear plant
with one input and one output the gain passes for the sensor's (``sensor_gain``); with more
outputs it scales all of them at once, and the held-out choice tells them apart."""
from __future__ import annotations

from ..catalogue_common import ParamSpec, fresh_name
from .base import Kind, Proposal, register
from .signal_common import input_record


@register
class InputGain(Kind):
    name = "input_gain"
    doors = ("input",)

    def propose(self, site):
        record = input_record(site)
        gain, about = fresh_name(site.taken, f"gain_{site.name}"), fresh_name(site.taken, f"rest_{site.name}")
        return [Proposal((ParamSpec(gain, 1.0, 0.2, 5.0, "1", f"gain of what input {site.name} delivers"),),
                         constants=((about, float(record.rest), record.unit,
                                     f"the value of {site.name} the gain scales about (where it rests)"),),
                         starts=({gain: 0.8}, {gain: 1.25}))]

    def build(self, graph, cand, values):
        u, (zero, *_) = cand.place.name, cand.constants[0]
        return graph.route_input(u, f"({zero} + {cand.params[0].name}*({u} - {zero}))")

    def explain(self, cand, values, show):
        u, (_, zero, unit, _) = cand.place.name, cand.constants[0]
        about = f" about {zero:.4g} {unit}".rstrip() if zero else ""
        return (f"the plant receives {show(cand.params[0].name)} times what input {u} records{about}: a gain "
                f"error of the actuator or sensor on input {u}")
