"""What the actuator (input) and sensor (output) kinds share.

The recorded input ``u`` stays the model's input; the elements that used it see an effective
input instead (:meth:`bondgraph.editing.GraphEditing.route_input`).  Added states start where the
input was before the experiment (:func:`resting_input`: the value at which the nominal initial
state is at rest, usually 0), so the first command step goes through the effect too.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import BondcosimError

__all__ = ["InputRecord", "input_record", "resting_input", "trial_times"]


@dataclass(frozen=True)
class InputRecord:
    """The recorded input at an input site (or a unit span about its default without data)."""

    values: np.ndarray
    unit: str
    rest: float
    #: whether the initial state told where the input rested (else `rest` is its first recorded value)
    told: bool = True

    @property
    def lo(self) -> float:
        return float(np.min(self.values))

    @property
    def hi(self) -> float:
        return float(np.max(self.values))

    @property
    def width(self) -> float:
        """The recorded span, or for a constant input a billionth of its size (at least 1e-12): a
        span that a bound or start a fraction of it away from the level still resolves in floating
        point (a supply pressure held at 333 kPa had ``lo - width == lo`` at a floor of 1e-12)."""
        return max(self.hi - self.lo, 1e-9 * max(abs(self.lo), abs(self.hi)), 1e-12)

    @property
    def mid(self) -> float:
        return float(np.median(self.values))


def input_record(site) -> InputRecord:
    """The input of an input `site`: recorded values, unit and resting value (computed once per site)."""
    if "input" not in site.shared:
        site.shared["input"] = _input_record(site)
    return site.shared["input"]


def _input_record(site) -> InputRecord:
    decl = next(d for d in site.graph.inputs() if d.name == site.name)
    recorded = site.recorded
    values = (np.asarray(recorded, dtype=float) if recorded is not None
              else np.array([decl.default - 1.0, decl.default + 1.0]))
    return InputRecord(values, decl.unit, *_resting(site.graph, site.name, recorded, site.x0))


#: the time constants or delays a fit starts from, in samples (each four times the last)
TRIAL_SAMPLES = (0.5, 2, 8, 32, 128, 512)


def trial_times(site) -> list[float]:
    """Time constants or delays the fit starts from: :data:`TRIAL_SAMPLES` under a quarter of the
    record.  Up to 32 samples only, a force-driven carriage's 3 s actuator lag (600 samples at 200
    Hz) was never started near: the fit from 0.16 s was given up (seed 8282, case 000)."""
    return [k * site.scales.dt for k in TRIAL_SAMPLES if k * site.scales.dt < site.scales.span / 4]


def resting_input(graph, u: str, recorded, x0=None) -> float:
    """The value of input `u` before the experiment: where the recording's initial state rests.

    Of 0, the input's default, its first recorded value and 33 values across its recorded range
    (refined between the best one's neighbours among them all), the one at which the initial
    state `x0` (dict state name -> value; default the model's) is closest to rest: the rates
    :math:`|f_i(x_0, u)|` (other inputs at their defaults) are normalised per state by their
    largest value over the trials, summed, and the smallest sum wins (ties: in that order).  A
    valve that held a joint at rest at 5 V before the record began rested at 5 V, whatever its
    first command.  The first recorded value when the model cannot be evaluated, or when the
    rates do not depend on the input at all (nothing says where it rested: the actuator is taken
    to have followed its first command).
    """
    return _resting(graph, u, recorded, x0)[0]


def _resting(graph, u: str, recorded, x0=None) -> tuple[float, bool]:
    """:func:`resting_input`'s value, and whether the initial state told it (False: the first
    recorded value, taken because nothing said where the input rested)."""
    from scipy.optimize import minimize_scalar

    from bondgraph.numerics.evaluate import compile_model
    decl = next(d for d in graph.inputs() if d.name == u)
    first = float(recorded[0]) if recorded is not None else float(decl.default)
    options = [0.0, float(decl.default), first]
    if recorded is not None and np.ptp(recorded) > 0:
        options += list(np.linspace(float(np.min(recorded)), float(np.max(recorded)), 33))
    try:
        eqs = graph.equations()
        model = compile_model(eqs, backend="numpy")
        base = np.array([float(eqs.input_defaults.get(n, 0.0)) for n in model.input_names])
        column = list(model.input_names).index(u)
        state = np.array(model.default_state, dtype=float)
        for i, name in enumerate(model.state_names):
            if x0 is not None and name in x0:
                state[i] = float(x0[name])

        def rates(values):
            trials = np.tile(base, (len(values), 1))
            trials[:, column] = values
            out = model.f(np.tile(state, (len(values), 1)), trials)
            return np.abs(np.asarray(out, dtype=float)).reshape(len(values), -1)

        r = rates(options)
    except (BondcosimError, ValueError, TypeError):
        return first, False
    if not np.isfinite(r).all() or np.allclose(r, r[0], rtol=1e-12, atol=0.0):
        return first, False
    peak = r.max(axis=0)
    moving = peak > 0

    def score(values):
        return (rates(values)[:, moving] / peak[moving]).sum(axis=1)

    scores = (r[:, moving] / peak[moving]).sum(axis=1)
    best = int(np.argmin(scores))
    if scores[best] == 0.0:
        return options[best], True
    # between the best one's neighbours among all the trials: a rest outside the recorded range
    # (levels that never went down to the inflow the tanks rested at) lies between 0 and its edge
    ordered = sorted(set(options))
    k = ordered.index(options[best])
    lo, hi = ordered[max(k - 1, 0)], ordered[min(k + 1, len(ordered) - 1)]
    if hi <= lo:
        return options[best], True
    found = minimize_scalar(lambda v: float(score([v])[0]), bounds=(lo, hi), method="bounded",
                            options={"xatol": 1e-6 * (ordered[-1] - ordered[0])})
    return (float(found.x) if found.success and found.fun < scores[best] else options[best]), True
