"""``saturation``: something that stops at a limit, at three kinds of place.

* a C's content :math:`q` at a junction (the storage is full, an axis is at its end), one
  candidate per C whose content moves in the nominal simulation: at a 1-junction, end stops, an R
  whose effort :math:`k_{stop} (\\max(q - q_{max}, 0) + \\min(q - q_{min}, 0))` pushes back beyond
  either limit; at a 0-junction, an overflow, an R whose flow :math:`k_{of} \\max(q - q_{max}, 0)`
  spills what exceeds the limit.  An end stop's stiffness is fitted with its limits: a rigid wall
  (30 times the junction's stiffness scale) and a bumper as soft as the C itself (a rubber stop,
  a second spring that engages) are both end stops, and a fixed wall cannot stand for the soft one.
  The overflow rate is fixed, :math:`k_{of}` one fifth of a sample's worth per second, so the
  content stays within a few per cent of the limit;
* an input: :math:`\\min(\\max(u, u_{min}), u_{max})` (routed as in
  :mod:`~diagnosis.kinds.signal_common`);
* an output, the sensor's range: :math:`\\min(\\max(y, y_{min}), y_{max})`.
"""
from __future__ import annotations

import numpy as np
import sympy as sp
from bondgraph import R

from ..catalogue_common import RELEASED, ParamSpec, fresh_name, junction_domain, released
from ..residuals import noise_sigma
from .base import Kind, Proposal, hang, register
from .feature_signals import FeatureGroup
from .signal_common import input_record
from .storage_common import capacitors, stiffness_scale, units_of


#: the shares of an input's samples beyond a limit at which one limit starts alone (a limit may
#: clip a few per cent of the samples by a little: a command's extreme levels)
ONE_SIDED = (0.01, 0.02, 0.05, 0.1, 0.25)
#: and both limits together
BOTH_SIDES = (0.02, 0.1, 0.25)
#: how far inside an input's recorded span (a fraction of it) its limits also start
INSIDE = (0.1, 0.25, 0.5)
#: how many noise standard deviations inside the recorded extremes a sensor's range may end
_RANGE_NOISE = 6.0
#: the limits the features try: (upper, lower) quantiles of the C's content
FEATURE_STOPS = ((0.75, 0.25), (0.9, 0.1), (0.97, 0.03))


@register
class Saturation(Kind):
    name = "saturation"
    doors = ("1", "0", "input", "output")
    feature_doors, feature_names, feature_price = "01", ("max(q - q_hi, 0)", "min(q - q_lo, 0)"), 2

    def features(self, s):
        """Per moving C content q: what exceeds limits at quantiles of q (both sides at a
        1-junction's end stops, the upper one at a 0-junction's overflow)."""
        out = []
        for c, q in s.labelled("content").items():
            for hi, lo in FEATURE_STOPS:
                top, bottom = np.quantile(q, hi), np.quantile(q, lo)
                cols = [np.maximum(q - top, 0.0)] + ([np.minimum(q - bottom, 0.0)] if s.one else [])
                out.append(FeatureGroup(c, f"q in [{bottom:.3g}, {top:.3g}]",
                                        ["max(q - q_hi, 0)", "min(q - q_lo, 0)"][:len(cols)], np.stack(cols, axis=1),
                                        (float(bottom), float(top))))
        return out

    def feature_start(self, cand, evidence):
        """End stops where the regression's hinges were, their stiffness its coefficient (the
        effort pushed back per unit beyond the limit); a side the regression found no push on
        starts beyond the content's range.  The open-loop error of a mass bouncing off a stop is
        steep and rugged in the stop's stiffness and position, and this start is already near."""
        if cand.place.kind != "junction" or len(cand.params) != 3 or len(evidence.grid) != 2:
            return None
        q_min, q_max, k = cand.params
        bottom, top = evidence.grid
        up = evidence.coefficients.get("max(q - q_hi, 0)", 0.0)
        down = evidence.coefficients.get("min(q - q_lo, 0)", 0.0)
        pushes = [c for c in (up, down) if np.isfinite(c) and c > 0]
        if not pushes:
            return None
        return {q_min.name: q_min.clipped(bottom if down > 0 else q_min.guess),
                q_max.name: q_max.clipped(top if up > 0 else q_max.guess),
                k.name: k.clipped(max(pushes))}

    def combined_starts(self, cand, tried):
        """A range's two limits act on different samples, so the limits tried alone are tried again
        with the other side at the best start's limit: an input clipped a little on both sides by
        different amounts (the exoskeleton's motor torque, seed 4747, case 005) is met by no start
        that moves both limits by the same quantile, and one side tried alone is judged with the
        other side's error still in the residual."""
        if len(cand.params) != 2 or len(tried) < 2:
            return []
        low, high = (spec.name for spec in cand.params)
        outer_low, outer_high = min(s[low] for s, _ in tried), max(s[high] for s, _ in tried)
        best = min(tried, key=lambda sc: sc[1])[0]
        lows = {s[low] for s, _ in tried if s[high] == outer_high and s[low] != outer_low}
        highs = {s[high] for s, _ in tried if s[low] == outer_low and s[high] != outer_high}
        pairs = {(best[low], h) for h in highs} | {(lo, best[high]) for lo in lows}
        seen = {(s[low], s[high]) for s, _ in tried}
        return [{low: a, high: b} for a, b in sorted(pairs - seen) if a < b]

    def propose(self, site):
        if site.door == "input":
            return [_input_range(site)]
        if site.door == "output":
            return [_sensor_range(site)]
        out = []
        for element in capacitors(site):
            q = site.values.get(f"state:{element.state}")
            if q is not None and np.ptp(q) > 0 and element.state:
                out.append(_content_limit(site, element, q))
        return out

    def build(self, graph, cand, values):
        p = [spec.name for spec in cand.params]
        name = cand.place.name
        if cand.place.kind == "output":
            lo, hi = sp.Symbol(p[0]), sp.Symbol(p[1])
            return graph.with_output(name, lambda y: sp.Min(sp.Max(y, lo), hi))
        if cand.place.kind == "input":
            return graph.route_input(name, f"Min(Max({name}, {p[0]}), {p[1]})")
        q = cand.regime
        if graph.elements[name].kind == "0":
            law = {"flow": f"{cand.constants[0][0]}*Max({q} - {p[0]}, 0)"}
        else:
            law = {"effort": f"{p[2]}*(Max({q} - {p[1]}, 0) + Min({q} - {p[0]}, 0))"}
        return hang(graph, R(f"limit_{cand.target}", domain=junction_domain(graph, name), **law,
                             description=f"limits of the content of {cand.target}"), name)

    def settle(self, cand, values, experiment):
        """An input limit that no training sample goes beyond has no evidence behind it: it is
        released (:data:`~diagnosis.catalogue_common.RELEASED`: no limit on that side)."""
        if cand.place.kind == "input" and experiment is not None and cand.place.name in experiment.inputs:
            u = np.asarray(experiment.inputs[cand.place.name], dtype=float)
            low, high = cand.params
            if not np.any(u < values[low.name]):
                values[low.name] = -RELEASED
            if not np.any(u > values[high.name]):
                values[high.name] = RELEASED
        return values

    def explain(self, cand, values, show):
        name = cand.place.name
        p = [spec.name for spec in cand.params]
        if cand.place.kind == "output":
            return (f"the {name} sensor reads nothing {_range(values, p, show)}: "
                    f"the range of the {name} sensor (saturation of output {name})")
        if cand.place.kind == "input":
            return f"the input {name} has no effect {_range(values, p, show)}: saturation of input {name}"
        if len(p) == 1:
            return (f"the storage {cand.target} at {name} holds no more than {show(p[0])}: what exceeds it "
                    f"overflows (saturation of {cand.target})")
        return (f"the content of {cand.target} at {name} is pushed back {_range(values, p[:2], show)} by end "
                f"stops of stiffness {show(p[2])} (saturation of {cand.target})")


def _range(values, names, show) -> str:
    """``beyond lo .. hi``, or the one finite side of a range whose other limit was released."""
    lo, hi = names
    if released(values[lo]) and not released(values[hi]):
        return f"above {show(hi)}"
    if not released(values[lo]) and released(values[hi]):
        return f"below {show(lo)}"
    return f"beyond {show(lo)} .. {show(hi)}"


def _content_limit(site, element, q) -> Proposal:
    """End stops (1-junction) or an overflow (0-junction) of C `element` (content trajectory `q`)."""
    c, taken = element.name, site.taken
    stiffness_unit, q_unit = units_of(element)
    lo, hi = float(np.min(q)), float(np.max(q))
    width = hi - lo
    q_max = fresh_name(taken, f"q_max_{c}")
    if site.door == "0":
        k = fresh_name(taken, f"k_of_{c}")
        return Proposal(target=c, regime=element.state,
                        constants=((k, 1.0 / (5.0 * site.scales.dt), "1/s", f"overflow rate of {c} beyond its limit"),),
                        starts=tuple({q_max: lo + f * width} for f in (0.95, 0.8, 0.6)),
                        params=(ParamSpec(q_max, hi + 1e-3 * width, lo, hi + width, q_unit,
                                          f"content of {c} beyond which it overflows"),))
    q_min, k = fresh_name(taken, f"q_min_{c}"), fresh_name(taken, f"k_stop_{c}")
    wall = 30.0 * stiffness_scale(site, element)
    soft = min(_own_stiffness(element) or wall / 1e3, wall)
    positions = ([{q_min: lo - 1e-3 * width, q_max: lo + f * width} for f in (0.9, 0.7, 0.4)]
                 + [{q_min: lo + f * width, q_max: hi + 1e-3 * width} for f in (0.1, 0.3, 0.6)])
    # a wall engages near the extremes; a bumper as soft as the spring may engage anywhere
    starts = [{**at, k: wall} for at in positions[:2] + positions[3:5]]
    starts += [{**at, k: soft} for at in positions]
    return Proposal(target=c, regime=element.state, starts=tuple(starts), params=(
        ParamSpec(q_min, lo - 1e-3 * width, lo - width, hi, q_unit, f"lower end stop of {c}"),
        ParamSpec(q_max, hi + 1e-3 * width, lo, hi + width, q_unit, f"upper end stop of {c}"),
        ParamSpec(k, wall, soft / 10.0, 100.0 * wall, stiffness_unit, f"stiffness of the end stops of {c}")))


def _own_stiffness(element) -> float | None:
    """A linear C's stiffness (its value, or one over its compliance); None for a law."""
    value = element.value
    if value is None or not float(value.value) > 0:
        return None
    return float(value.value) if element.stiffness_form else 1.0 / float(value.value)


def _input_range(site) -> Proposal:
    """Limits of an input, started one side at a time then both, from the recorded quantiles."""
    u, rec = site.name, input_record(site)
    lo, hi, width, mid, values = rec.lo, rec.hi, rec.width, rec.mid, rec.values
    q_lo, q_hi = (float(v) for v in np.percentile(values, [5, 95]))
    q_lo, q_hi = min(q_lo, mid - 1e-3 * width), max(q_hi, mid + 1e-3 * width)
    u_min, u_max = fresh_name(site.taken, f"u_min_{u}"), fresh_name(site.taken, f"u_max_{u}")
    # a thousandth of the span inside each quantile: an input of held levels has its quantiles AT
    # its levels, where a limit clips nothing and the fit sees no gradient; just inside, it clips
    # that level a little and sees which way to go
    limits = [(float(np.quantile(values, q)) + 1e-3 * width, float(np.quantile(values, 1 - q)) - 1e-3 * width)
              for q in ONE_SIDED]
    # each side is judged on its own: a lower limit must leave the recorded top, an upper one the
    # bottom.  Judged against the median, a two-level input with more samples at its low level
    # (the median AT that level) lost every one of them, and its fit started only a tenth of the
    # span inside, where clipping a level by far more than the truth does loses to clipping nothing
    # (seed 4242, case 020: a pump's high level clipped by 1.7 %)
    lowers = list(dict.fromkeys(a for a, _ in limits if a < hi))
    uppers = list(dict.fromkeys(b for _, b in limits if b > lo))
    # one-sided starts first: on a tie (no sample beyond a limit) the limit stays inactive
    starts = [{u_min: lo - 1e-3 * width, u_max: b} for b in uppers]
    starts += [{u_min: a, u_max: hi + 1e-3 * width} for a in lowers]
    starts += [s for s in ({u_min: a, u_max: b} for (a, b), q in zip(limits, ONE_SIDED) if q in BOTH_SIDES and a < b)
               if s not in starts]
    # an input of a few held levels (a PRBS, steps) has its quantiles AT its levels, where a limit
    # clips nothing and the fit sees no gradient: start each side inside the recorded span too, a
    # tenth of it in as well (a start that clips a level by far more than the truth does costs more
    # than clipping nothing, and the fit then starts where it sees no gradient: seed 9494, case 059)
    inside = [s for f in INSIDE for s in ({u_min: lo - 1e-3 * width, u_max: max(hi - f * width, lo)},
                                          {u_min: min(lo + f * width, hi), u_max: hi + 1e-3 * width})]
    # both sides at once: a two-level input clipped on both levels is clipped nowhere by one side alone
    inside += [{u_min: lo + f * width, u_max: hi - g * width} for f in INSIDE[:-1] for g in INSIDE[:-1]]
    starts += [s for s in inside if hi > lo and not any(
        abs(s[u_min] - t[u_min]) + abs(s[u_max] - t[u_max]) < 0.02 * width for t in starts)]
    # a recording of a saturated input has many samples AT the limit: its median may be the limit
    # itself, so each limit may range over the whole recorded span
    return Proposal(starts=tuple(starts), params=(
        ParamSpec(u_min, q_lo, lo - width, hi, rec.unit, f"lower saturation of {u}"),
        ParamSpec(u_max, q_hi, lo, hi + width, rec.unit, f"upper saturation of {u}")))


def _sensor_range(site) -> Proposal:
    """The range of a sensor, from the measured output."""
    y, measured = site.name, site.recorded
    unit = site.graph.outputs[y].unit
    width = float(np.ptp(measured)) if measured is not None and np.ptp(measured) > 0 else 1.0
    values = np.asarray(measured, dtype=float) if measured is not None else np.array([-1.0, 1.0])
    lo, hi = float(np.min(values)), float(np.max(values))
    y_min, y_max = fresh_name(site.taken, f"y_min_{y}"), fresh_name(site.taken, f"y_max_{y}")
    # a sensor reads nothing beyond its range but its noise: each limit lies beyond every recorded
    # sample, but for a few noise standard deviations (and its resolution).  A limit inside the
    # recorded span would clip values the sensor did read; on a drifting model it would still cut
    # the training error where the drift leaves the data (seed 6868, case 042: a lower limit at
    # -3.2 m under a record that reads -3.3 m, its held-out error 25 times the nominal's)
    margin = min(_RANGE_NOISE * noise_sigma(values), 0.5 * width) if values.size > 3 else 0.05 * width
    starts = [{y_min: lo - 1e-3 * width, y_max: hi - f * margin} for f in (0.0, 1.0)]
    starts += [{y_min: lo + f * margin, y_max: hi + 1e-3 * width} for f in (0.0, 1.0)]
    return Proposal(starts=tuple(starts), params=(
        ParamSpec(y_min, lo - 1e-3 * width, lo - width, lo + margin, unit, f"lower end of the {y} sensor's range"),
        ParamSpec(y_max, hi + 1e-3 * width, hi - margin, hi + width, unit, f"upper end of the {y} sensor's range")))
