"""``valve_lag`` on an input: :math:`\\tau \\dot x = u - x`, effective input :math:`x` (an extra
state, starting at the input's resting value, :func:`~diagnosis.kinds.signal_common.resting_input`)."""
from __future__ import annotations

from ..catalogue_common import ParamSpec, fresh_name
from .base import Kind, Proposal, register
from .signal_common import input_record, trial_times


@register
class ValveLag(Kind):
    name = "valve_lag"
    doors = ("input",)

    def propose(self, site):
        u, span, dt = site.name, site.scales.span, site.scales.dt
        tau = fresh_name(site.taken, f"tau_lag_{u}")
        return [Proposal(initial={f"x_lag_{u}": input_record(site).rest},
                         starts=tuple({tau: v} for v in trial_times(site)),
                         params=(ParamSpec(tau, max(5 * dt, span / 100), dt / 20, span / 2, "s",
                                           f"time constant of the actuator lag on {u}"),))]

    def build(self, graph, cand, values):
        u, tau = cand.place.name, cand.params[0].name
        unit = next(d.unit for d in graph.inputs() if d.name == u)
        x = f"x_lag_{u}"
        return graph.route_input(u, x, states={x: f"({u} - {x})/{tau}"}, initial=dict(cand.initial), units={x: unit})

    def explain(self, cand, values, show):
        u = cand.place.name
        return (f"the actuator driven by {u} follows its command with a lag of {show(cand.params[0].name)}: "
                f"a first-order valve/actuator lag on input {u}")
