"""``sensor_lag`` on an output: the sensor reads the model output ``y`` through a first-order lag,
:math:`\\tau \\dot y_s = y - y_s`, and reports :math:`y_s` (a thermocouple's own heat capacity, a
pressure transducer behind a line, a load cell's or an encoder's filter).

The lag's state belongs to an equation element without ports
(:meth:`bondgraph.editing.GraphEditing.sense_output`).  It starts at what the sensor read first
(the median of the first three samples): a sensor's state is its own reading, whatever the plant's
state.  On a plant with one input and one output that is linear, an actuator lag
(``valve_lag``) passes for it exactly (the two first-order factors commute); a second output
the input drives without the lag, or a nonlinearity between them, tells them apart.  Its time
constant is at most the commands' median hold (:func:`~diagnosis.catalogue_scales.command_hold`):
a sensor slower than the steps it logs would show none of them, while an actuator may be that
slow (a carriage whose force lagged 1.7 s behind commands held 0.2 s, with a wrong first answer
in place, was answered a 0.54 s lag of its velocity sensor).
"""
from __future__ import annotations

import numpy as np
import sympy as sp

from ..catalogue_common import ParamSpec, fresh_name
from .base import Kind, Proposal, register
from .signal_common import trial_times

#: samples at the start of the record whose median the sensor's state starts from
FIRST_SAMPLES = 3


@register
class SensorLag(Kind):
    name = "sensor_lag"
    doors = ("output",)
    unranked_sensor = False

    def propose(self, site):
        y, span, dt = site.name, site.scales.span, site.scales.dt
        tau = fresh_name(site.taken, f"tau_sensor_{y}")
        state = fresh_name(site.taken, f"y_lag_{y}")
        first = 0.0 if site.recorded is None else float(np.median(np.asarray(site.recorded)[:FIRST_SAMPLES]))
        # a sensor follows the commands' steps: a lag beyond the levels' typical hold would show
        # none of them (an actuator may be that slow, a logged sensor is not)
        upper = min(span / 2, site.scales.hold) if site.scales.hold else span / 2
        guess = min(max(5 * dt, span / 100), upper / 2)
        return [Proposal(initial={state: first},
                         starts=tuple({tau: v} for v in trial_times(site) if v < upper),
                         params=(ParamSpec(tau, guess, dt / 20, upper, "s", f"time constant of the {y} sensor"),))]

    def build(self, graph, cand, values):
        y, tau = cand.place.name, sp.Symbol(cand.params[0].name)
        (state, first), = cand.initial.items()
        z = sp.Symbol(state)
        return graph.sense_output(y, {state: lambda out: (out - z) / tau}, z, initial={state: first},
                                  units={state: graph.outputs[y].unit}, element=f"sensor_{state}",
                                  description=f"first-order lag of the {y} sensor")

    def explain(self, cand, values, show):
        y = cand.place.name
        return (f"the {y} sensor follows the true value with a lag of {show(cand.params[0].name)}: "
                f"a first-order sensor lag on output {y}")
