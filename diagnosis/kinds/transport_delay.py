"""``transport_delay`` on an input: :math:`u(t - T)`, realised as the strictly proper Padé [2/3]
approximant of :math:`e^{-sT}`,

.. math:: \\frac{1 - \\tfrac25 sT + \\tfrac1{20}(sT)^2}
                {1 + \\tfrac35 sT + \\tfrac3{20}(sT)^2 + \\tfrac1{60}(sT)^3},

in controllable canonical form: three states owned by the element that reads ``u``, with
:math:`T` a parameter.  FMI has no delay primitive, and a Padé chain is ordinary states, so the
graph exports (Model Exchange and Co-Simulation) like any other.  Error :math:`O((sT)^6)`; a step
is reproduced without a jump at t = 0 (strictly proper).
"""
from __future__ import annotations

from ..catalogue_common import ParamSpec, fresh_name
from .base import Kind, Proposal, register
from .signal_common import input_record, trial_times


@register
class TransportDelay(Kind):
    name = "transport_delay"
    doors = ("input",)

    def propose(self, site):
        u, span, dt = site.name, site.scales.span, site.scales.dt
        delay = fresh_name(site.taken, f"T_delay_{u}")
        return [Proposal(initial={f"z1_delay_{u}": input_record(site).rest},
                         starts=tuple({delay: v} for v in trial_times(site)),
                         params=(ParamSpec(delay, max(3 * dt, span / 200), dt / 20, span / 4, "s",
                                           f"transport delay of {u}"),))]

    def build(self, graph, cand, values):
        u, T = cand.place.name, cand.params[0].name
        unit = next(d.unit for d in graph.inputs() if d.name == u)
        z1, z2, z3 = (f"z{i}_delay_{u}" for i in (1, 2, 3))
        states = {z1: z2, z2: z3, z3: f"60*({u} - {z1} - 3*{T}/5*{z2} - 3*{T}**2/20*{z3})/{T}**3"}
        return graph.route_input(u, f"{z1} - 2*{T}/5*{z2} + {T}**2/20*{z3}", states=states,
                                 initial={z1: cand.initial.get(z1, 0.0), z2: 0.0, z3: 0.0},
                                 units={z1: unit, z2: f"({unit})/s", z3: f"({unit})/s^2"})

    def explain(self, cand, values, show):
        u = cand.place.name
        return (f"the input {u} acts {show(cand.params[0].name)} late: a transport delay on input {u} "
                "(Pade [2/3] states in the model)")
