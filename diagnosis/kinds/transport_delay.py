"""``transport_delay`` on an input: the elements that read ``u`` read :math:`u(t - T)`, with
:math:`T` a parameter (:meth:`bondgraph.editing.GraphEditing.delay_input`).

The delay is realised on the recorded samples, not by states: a Pade chain or a lag reads the
command of the previous sample interval, so an output that reads the input directly (a force
:math:`pA`, a velocity :math:`(x - x_s)/\\tau`) would be a sample late whatever :math:`T` is,
while a delay of whole samples shifts the record exactly (:mod:`bondgraph.numerics.input_delays`).
Before the record the input is where it rested (:func:`~diagnosis.kinds.signal_common.resting_input`);
where the initial state cannot tell (no state depends on the input: a force ``p A`` on a piston
whose motion is imposed), that value is fitted with the delay (:func:`value_before`): a record
that starts with the command at 5.8 bar, after a pressure that rested at 0, leaves the delay's
first :math:`T` seconds wrong at any fixed guess (seed 1919, case 012).
The fit starts from whole numbers of samples (:func:`delay_trials`).
The graph exports to an FMU with the delay as Pade [2/3] states
(:meth:`~bondgraph.editing.GraphEditing.with_delays_realised`).
"""
from __future__ import annotations

import numpy as np

from ..catalogue_common import ParamSpec, fresh_name
from .base import Kind, Proposal, register
from .signal_common import input_record


@register
class TransportDelay(Kind):
    name = "transport_delay"
    doors = ("input",)

    def propose(self, site):
        u, span, dt = site.name, site.scales.span, site.scales.dt
        delay = ParamSpec(fresh_name(site.taken, f"T_delay_{u}"), max(3 * dt, span / 200), 0.0, span / 4, "s",
                          f"transport delay of {u}")
        rec = input_record(site)
        starts = tuple({delay.name: v} for v in delay_trials(site))
        if rec.told:
            return [Proposal(initial={_late(u): rec.rest}, starts=starts, params=(delay,))]
        before = value_before(site, rec)
        others = [v for v in (0.0, rec.rest) if before.lower <= v <= before.upper and v != before.guess]
        starts += tuple({**start, before.name: v} for v in others for start in starts)
        return [Proposal(starts=starts, params=(delay, before))]

    def build(self, graph, cand, values):
        from bondgraph import Param
        u, T = cand.place.name, cand.params[0].name
        late = fresh_name(frozenset(graph.names()), _late(u))
        before = cand.initial.get(_late(u))
        if len(cand.params) > 1:
            spec = cand.params[1]
            before = Param(spec.name, values[spec.name], unit=spec.unit, description=spec.description)
        return graph.delay_input(u, T, values[T], before=before, name=late)

    def combined_starts(self, cand, tried):
        """Every whole sample strictly between the best start's neighbouring starts: the fit cannot
        slide across samples (:func:`delay_trials`), and the first starts skip some (a pressure 5
        samples late, between the starts at 4 and 6, was fitted 6 late: seed 5757, case 041).
        The sample interval is twice the kind's first start (half a sample, :func:`delay_trials`;
        starts added after the kind's own, such as where an earlier fit ended, may be anywhere: one
        at 3 us made 74 000 starts of seed 3434's compound case 007).  The other parameters (a
        fitted value before the record) stay at the best start's."""
        T = cand.params[0]
        delays = sorted({start[T.name] for start, _ in tried})
        half = cand.starts[0].get(T.name, 0.0) if cand.starts else 0.0
        if len(delays) < 2 or not half > 0:
            return []
        dt, start = 2.0 * half, min(tried, key=lambda sc: sc[1])[0]
        best = start[T.name]
        below, above = [d for d in delays if d < best], [d for d in delays if d > best]
        first = int(np.floor((below[-1] if below else 0.0) / dt + 1e-9)) + 1
        last = int(np.ceil((above[0] if above else best) / dt - 1e-9)) - 1
        return [{**start, T.name: k * dt} for k in range(first, last + 1)
                if T.lower <= k * dt <= T.upper and not np.isclose(k * dt, delays, rtol=1e-9, atol=0.0).any()]

    def explain(self, cand, values, show):
        u = cand.place.name
        before = (f", and before the record it rested at {show(cand.params[1].name)} (fitted: the initial state "
                  "does not tell)" if len(cand.params) > 1 else "")
        return (f"the input {u} acts {show(cand.params[0].name)} late{before}: a transport delay on input {u} "
                "(exact on the recorded samples; Pade [2/3] states in an exported FMU)")


def value_before(site, rec) -> ParamSpec:
    """The input's value before the record, fitted (not priced: an initial condition, no physics):
    from its first recorded value, over the recorded range widened to take in 0 and the input's
    default (where a command rests when off), and a quarter of that span beyond."""
    decl = next(d for d in site.graph.inputs() if d.name == site.name)
    lo, hi = min(rec.lo, 0.0, decl.default), max(rec.hi, 0.0, decl.default)
    margin = max(hi - lo, rec.width) / 4
    return ParamSpec(fresh_name(site.taken, f"{site.name}_before"), rec.rest, lo - margin, hi + margin, rec.unit,
                     f"value of input {site.name} before the record", priced=False)


#: whole samples the fit of a delay starts from (those under a quarter of the record)
_WHOLE_SAMPLES = (1, 2, 3, 4, 6, 8, 12, 16, 24, 32, 48, 64)


def delay_trials(site) -> list[float]:
    """Delays the fit starts from, s: half a sample and whole samples up to 64.  An output that
    reads the delayed input directly sees a zero-order-hold command, whose value at a sample does
    not change while the delay moves inside one interval: the fit cannot slide across samples
    there, so it starts at each of them (one batch of runs, :func:`diagnosis.fit.fit_candidate`)."""
    dt, span = site.scales.dt, site.scales.span
    return [k * dt for k in (0.5, *_WHOLE_SAMPLES) if k * dt < span / 4]


def _late(u: str) -> str:
    """The delayed input's name (and the key of its value before the record in ``initial``)."""
    return f"{u}_late"
