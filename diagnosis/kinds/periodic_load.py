"""``periodic_load`` at a mechanical 1-junction: an effort that repeats with the position, not
with time or speed.

.. math::

    e = A \\sin(2\\pi\\theta / P) + B \\cos(2\\pi\\theta / P), \\qquad \\dot\\theta = f

taken from the junction, :math:`\\theta` the travel since the recording's start (an equation
element owns it, so a free mass or a shaft without a position state has one), the period
:math:`P` and both amplitudes fitted (the phase is their angle: where the travel started needs
no knowing).  Where it lives: a motor's cogging torque (a period of 2 pi over the slots or
poles), an unbalanced rotor or an arm's gravity torque (2 pi), a screw's lead error or a linear
motor's pole pitch (a period of its travel).  A load that varies with position over less than
two periods is a spring or a constant load, not this: only periods the record's travel covers
twice are tried (:func:`periods`), and only where the travel moves by at most a quarter of a
period per sample.

The features: :math:`\\sin` and :math:`\\cos` of :math:`2\\pi\\theta/P` for each trial period, or,
where the location estimated the junction's extra effort, for the few periods of a fine grid whose
sinusoid fits that estimate best (:func:`best_periods`); the fit starts at the chosen period with the
two coefficients as the amplitudes.
"""
from __future__ import annotations

import math

import numpy as np

from bondgraph import EquationElement

from ..catalogue_common import ParamSpec, junction_domain, junction_units
from .base import Kind, Proposal, hang, register
from .feature_signals import FeatureGroup
from .friction_common import displacement_unit, namer

#: the trial periods of a rotation: a revolution over these counts (an unbalance, cogging)
TURN_DIVISORS = (1, 2, 3, 4, 6, 8, 12, 16, 24, 32, 48, 64)
#: the fewest samples per period at the fastest travel: a sinusoid of the travel sampled coarser aliases
STEPS_PER_PERIOD = 4.0
#: the trial periods of any travel: its range over these counts (a screw's lead, a pole pitch)
RANGE_DIVISORS = (2.0, 2.8, 4.0, 5.7, 8.0, 11.3, 16.0, 22.6, 32.0)


def travel(flow, dt: float) -> np.ndarray:
    """The integral of `flow` from 0 at the first sample (trapezoids of step `dt`)."""
    flow = np.asarray(flow, float)
    return np.concatenate([[0.0], np.cumsum(0.5 * (flow[1:] + flow[:-1]) * dt)])


def periods(theta, rotation: bool) -> list[float]:
    """The trial periods for the travel `theta`: its range over :data:`RANGE_DIVISORS` (and, on a
    rotation, 2 pi over :data:`TURN_DIVISORS`), those the range covers twice and the largest
    step per sample resolves by :data:`STEPS_PER_PERIOD`."""
    theta = np.asarray(theta, float)
    if theta.size < 3 or not np.all(np.isfinite(theta)):
        return []
    span, step = float(np.ptp(theta)), float(np.max(np.abs(np.diff(theta))))
    trial = [span / c for c in RANGE_DIVISORS] + ([2 * math.pi / n for n in TURN_DIVISORS] if rotation else [])
    return sorted({round(p, 12) for p in trial if 0 < 2 * p <= span and p >= STEPS_PER_PERIOD * step})


#: the fine grid's step (a ratio of periods) and the number of its best periods the features try
FINE_STEP, PEAKS = 1.004, 3


def fine_periods(trial) -> np.ndarray:
    """Periods from the shortest to the longest of `trial`, :data:`FINE_STEP` apart, with the
    trial periods themselves (a turn over a whole number)."""
    low, high = min(trial), max(trial)
    grid = low * FINE_STEP ** np.arange(int(np.log(high / low) / np.log(FINE_STEP)) + 1)
    return np.unique(np.concatenate([grid, trial]))


def best_periods(theta, estimate, grid, peaks: int = PEAKS, rows: int = 4000) -> list[float]:
    """The `peaks` periods of `grid` whose sinusoid in `theta` (with a constant) leaves the least
    of `estimate` by least squares, each a local best, on at most `rows` samples."""
    take = np.arange(0, theta.size, max(1, theta.size // rows))
    x, d = theta[take], estimate[take] - estimate[take].mean()
    left = np.empty(grid.size)
    for i, p in enumerate(grid):
        basis = np.stack([np.sin(2 * np.pi * x / p), np.cos(2 * np.pi * x / p), np.ones_like(x)], axis=1)
        coef, *_ = np.linalg.lstsq(basis, d, rcond=None)
        left[i] = float(np.sum((d - basis @ coef) ** 2))
    local = [i for i in range(grid.size) if (i == 0 or left[i] <= left[i - 1]) and
             (i == grid.size - 1 or left[i] <= left[i + 1])]
    return sorted(float(grid[i]) for i in sorted(local, key=lambda i: left[i])[:peaks])


@register
class PeriodicLoad(Kind):
    name = "periodic_load"
    doors = ("1",)
    domains = ("translation", "rotation")
    feature_doors, feature_names, feature_price = "1", ("sin(2 pi theta/P)", "cos(2 pi theta/P)"), 3
    # three free numbers of the travel can stand in for a mass's error along a travel one way (seed
    # 7474's detuned carriage, case 024): fitted only where its features say so
    needs_evidence = True

    def features(self, s):
        """sin and cos of the travel for the trial periods; with the location's estimate, the
        :data:`PEAKS` periods of a fine grid whose sinusoid fits the estimate best (a period off
        by a step of the coarse grid dephases within a few periods of travel)."""
        theta = s.travel                      # the model's own integral of the flow, where read
        trial = periods(theta, s.domain == "rotation")
        estimate = s.values.get("estimate")
        if trial and estimate is not None and np.ptp(estimate) > 0:
            trial = best_periods(theta, np.asarray(estimate, float), fine_periods(trial))
        return [FeatureGroup(None, f"P = {p:.4g}", list(self.feature_names),
                             np.stack([np.sin(2 * np.pi * theta / p), np.cos(2 * np.pi * theta / p)], axis=1),
                             grid=(p,))
                for p in trial]

    def feature_start(self, cand, evidence):
        """The amplitudes at the two coefficients, the period at the grid's."""
        a, b = (evidence.coefficients.get(n) for n in self.feature_names)
        if a is None or b is None or not (np.isfinite(a) and np.isfinite(b)) or len(evidence.grid) != 1:
            return None
        sin_amp, cos_amp, period = cand.params
        return {sin_amp.name: sin_amp.clipped(float(a)), cos_amp.name: cos_amp.clipped(float(b)),
                period.name: period.clipped(float(evidence.grid[0]))}

    def propose(self, site):
        flow = site.values.get(f"f_{site.graph.bonds_of(site.name)[0][0].name}")
        rotation = junction_domain(site.graph, site.name) == "rotation"
        trial = periods(travel(flow, site.scales.dt), rotation) if flow is not None else []
        if not trial:
            return []                           # no travel it repeats over twice (or no data)
        j, E = site.name, site.scales.effort
        e_unit, f_unit = junction_units(site.graph, j)
        name = namer(site)
        a, b, p = name("A_periodic"), name("B_periodic"), name("P_periodic")
        middle = trial[len(trial) // 2]
        return [Proposal((
            ParamSpec(a, 0.0, -10 * E, 10 * E, e_unit, f"amplitude of the load at {j} in phase with sin(2 pi theta/P)"),
            ParamSpec(b, 0.0, -10 * E, 10 * E, e_unit, f"amplitude of the load at {j} in phase with cos(2 pi theta/P)"),
            ParamSpec(p, middle, 0.5 * trial[0], 2.0 * trial[-1], displacement_unit(f_unit),
                      f"period in travel of the load at {j}")),
            # from nothing the period has no gradient: start each trial period with a load
            starts=tuple({a: 0.1 * E, b: 0.0, p: q} for q in trial[::3]))]

    def build(self, graph, cand, values):
        j = cand.place.name
        a, b, p = (spec.name for spec in cand.params)
        state = f"theta_periodic_{j}"
        phase = f"2*pi*{state}/{p}"
        element = EquationElement(f"periodic_load_{j}", ports={"m": "in"},
                                  outputs={"e_m": f"{a}*sin({phase}) + {b}*cos({phase})"},
                                  states={state: "f_m"}, initial={state: 0.0},
                                  units={state: displacement_unit(junction_units(graph, j)[1])},
                                  description=f"load at {j} that repeats with its travel")
        return hang(graph, element, j)

    def explain(self, cand, values, show):
        j = cand.place.name
        a, b, p = (spec.name for spec in cand.params)
        amp = math.hypot(values.get(a, 0.0), values.get(b, 0.0))
        unit = cand.params[0].unit
        period = values[p]
        turns = (f" ({2 * math.pi / period:.3g} per revolution)" if cand.params[2].unit == "rad" else "")
        return (f"the motion at {j} meets a load of +-{amp:.3g} {unit} that repeats every {show(p)} of travel"
                f"{turns}: a position-periodic load (cogging, an unbalance, a lead error) at {j}")
