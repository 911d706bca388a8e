"""Restarting a model from the data: where a record is cut into segments, the state each
segment's simulation starts from, fitted to its first samples.

The held-out judge's segment error (:mod:`diagnosis.segments`) and multiple-shooting fits on
the training part (:mod:`diagnosis.shooting`) both cut a part of the recording into a
:class:`SegmentPlan` and restart each segment from :func:`restart_states`.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
import sympy as sp

__all__ = ["SegmentPlan", "carried_states", "restart_states", "input_driven_states", "state_spread"]


@dataclass(frozen=True)
class SegmentPlan:
    """Where a part of the recording (the held-out part, or the training part of a shooting fit)
    is cut.

    Attributes
    ----------
    starts : tuple of int
        First sample of each segment, index into the part.
    length : int
        Samples per segment (the last one takes the remainder).
    estimation : int
        Samples at the start of each segment its state is estimated from (not scored).
    seconds : float
        Duration of a segment, s.
    n : int
        Samples of the part.
    """

    starts: tuple
    length: int
    estimation: int
    seconds: float
    n: int

    def bounds(self):
        """``(first, stop)`` sample indices of each segment in the part."""
        stops = list(self.starts[1:]) + [self.n]
        return list(zip(self.starts, stops))

    def to_json(self) -> dict:
        return {"count": len(self.starts), "length": self.seconds, "samples": self.length,
                "estimation_samples": self.estimation}


def carried_states(sim, nominal_states=None) -> list:
    """Indices of the states of `sim`'s model a restart takes from the model's own run instead of
    fitting them: its own states (not among `nominal_states`, the plant's) that follow the inputs
    alone (:func:`input_driven_states`); none when `nominal_states` is None."""
    if nominal_states is None:
        return []
    own = {i for i, name in enumerate(sim.model.state_names) if name not in nominal_states}
    return [i for i in input_driven_states(sim.equations) if i in own] if own else []


def restart_states(sim, part, plan, noise: dict, params=None, prior=None, nominal_states=None, *,
                   covariance=False, starts=None, chained=False) -> list:
    """The state each segment of `plan` on `part` restarts from, fitted to its first
    ``plan.estimation`` samples: a list of ``(state, covariance)`` (covariance None unless asked
    for; state None where no state runs).

    Each is :func:`diagnosis.initial_state.fit_state`'s noise-weighted least squares, pulled
    weakly towards `prior` there (states on `part`'s grid, e.g. the model's open-loop run; the
    model's default where that is None or not finite).  Where `nominal_states` names the plant's
    states, a state of the candidate's own that follows the inputs alone (an actuator's lag,
    :func:`input_driven_states`) is not fitted but taken from `prior`, which has it exactly.
    `starts` (one state per segment, or None) replaces `prior` as each fit's start and pull, those
    carried states aside: the states a previous restart fitted, nearer than a drifted run's.

    `chained` (for a nominal's unstable mode): each segment's fit is also started from where the
    previous segment's simulation ends, and the fit that leaves its estimation samples the
    smaller error is kept.  The open-loop run such a model drifts from says nothing of the state
    by then, and a fit started there can settle in the wrong well of a double-well oscillator: the
    right Coulomb friction then predicted one segment of nine at the other well, and the held-out
    error was twice the nominal's."""
    from .initial_state import fit_state
    outputs = list(sim.output_names)
    default = sim.initial_state(None)
    spread = state_spread(prior, default.size)
    carried = carried_states(sim, nominal_states)
    is_carried = np.isin(np.arange(default.size), carried)
    found, follows = [], None
    for k, (a, b) in enumerate(plan.bounds()):
        known = prior is not None and np.isfinite(prior[a]).all()
        start = prior[a] if known else default
        if starts is not None and starts[k] is not None and np.isfinite(starts[k]).all():
            start = np.where(is_carried & known, start, starts[k])
        win = part.samples(a, a + plan.estimation)
        w_sim, y = sim.on(win), {o: np.asarray(win.outputs[o], float) for o in outputs}
        tries = [start] + ([np.where(is_carried & known, start, follows)] if chained and follows is not None else [])
        fits = []
        for x0 in tries:
            scale = np.maximum(np.maximum(np.abs(x0), spread), 1e-9)
            scale = np.where(scale > 1e-9, scale, 1.0)
            fits.append(fit_state(w_sim, y, noise, x0, scale, params=params, covariance=covariance,
                                  kept=carried if known else ()))
        x = fits[0] if len(fits) == 1 else min(
            fits, key=lambda f: _window_cost(w_sim, y, noise, f[0] if covariance else f, params))
        found.append(x if covariance else (x, None))
        follows = _end_state(sim, part, a, b, x[0] if covariance else x, params) if chained else None
    return found


def state_spread(prior, size: int) -> np.ndarray:
    """Each state's standard deviation over the run `prior` (zeros where there is none, or it
    leaves the finite numbers): a scale beside the state's own size."""
    if prior is None or not np.isfinite(prior).all():
        return np.zeros(size)
    return np.nanstd(prior, axis=0)


def _window_cost(w_sim, y, noise, x, params) -> float:
    """The noise-weighted squared error of the outputs `y` simulated from `x` (inf where none)."""
    from .errors import BondcosimError
    if x is None:
        return float("inf")
    try:
        out = w_sim(params, x)
    except BondcosimError:
        return float("inf")
    cost = sum(float(np.sum(((y[o] - out[o]) / max(noise.get(o, 0.0), 1e-300)) ** 2)) for o in y)
    return cost if np.isfinite(cost) else float("inf")


def _end_state(sim, part, a, b, x, params):
    """The state at sample `b` of `part` (the next segment's first) simulated from `x` at sample
    `a`, or None where it does not run or `b` is past the part."""
    from .errors import BondcosimError
    if x is None or b >= part.t.size:
        return None
    try:
        states = sim.on(part.samples(a, b + 1)).run(params, x).states
    except BondcosimError:
        return None
    return states[-1] if np.isfinite(states[-1]).all() else None


@functools.lru_cache(maxsize=64)
def input_driven_states(equations) -> tuple:
    """Indices of the states whose right-hand side reads no other state nor any algebraic or held
    variable: an actuator's lag, a filter of a command, but also a free mass's momentum under a
    force.  Where a candidate adds such a state (its own, not the plant's), it follows the inputs
    alone from a known start, so the candidate's open-loop run has it exactly, drift or no drift,
    and a segment restart takes it from there (:meth:`Judge.segment_error`); the plant's own
    states are restarted, since what the model leaves out acts on them.  Fitted to a segment's
    first samples instead, an actuator's state would be a free effort or flow per segment: a
    3.5 s lag on the carriage's force, restarted every 0.6 s, stood for a force the actuator
    could not deliver and beat the fitted saturation of that force (seed 4747, case 077)."""
    others = set(equations.states) | set(equations.algebraic) | set(equations.held)
    return tuple(i for i, (x, f) in enumerate(zip(equations.states, equations.f))
                 if not (sp.sympify(f).free_symbols & others) - {x})
