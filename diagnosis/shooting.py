"""Fitting by the segment judge's own error: multiple shooting on the training part.

Under the segment judge (:mod:`diagnosis.segments`: the nominal model drifts or diverges) a
candidate is judged by how well it predicts short segments of the held-out part, each restarted
from a state fitted to its first samples.  Where the judge took the nominal for an unstable mode
(:attr:`Judge.unstable <diagnosis.segments.Judge.unstable>`: an error grows e-fold within the
held-out part), the candidates are fitted by that error too.  Fitted open-loop over the whole training part
instead, from the recording's first state, its training error is whatever the accumulated
drift of the whole run makes it: where the plant is sensitive to its state, even the right
law fitted so may not get there (a pendulum driven over the top by a torque, its pivot
friction missing: the nominal turns a revolution behind within seconds, and every friction
law fitted open-loop over 21 s explained nothing, answer ``none``); an integrator's error (a
force-driven carriage) only accumulates, and its open-loop fits stay.  So here the training part
is cut the way the judge cuts the held-out part (:class:`Shooting`): segments of the judge's
length, each restarted from a state fitted to its first samples
(:func:`diagnosis.restarts.restart_states`), scored on the rest.

The restart states are fitted at the parameters a search starts from (with each segment's
sensitivity to its state), and while the parameters move they follow to first order: each
evaluation is one simulation of each segment, corrected by the state change its estimation
samples ask for (:meth:`Shooting.__call__`, a linearised variable projection).  Held fixed
instead, they kept what the guess's model made of the estimation samples (a pendulum's speed
estimated without its drag), and the fit stopped a fifth short of the drag, or was given up.
The states are fitted again at the parameters found and the search resumes there, until the
parameters stay where they are (:data:`PASSES`, :data:`SETTLED`).
"""
from __future__ import annotations

import numpy as np

from .errors import BondcosimError
from .restarts import SegmentPlan, carried_states, restart_states, state_spread

__all__ = ["Shooting", "training_plan", "fitted_from", "PASSES", "FIRST_PASS", "SETTLED"]

#: forward-difference step of a restart state, relative to its size (or its spread over the run)
_STATE_STEP = 1e-6
#: at most this many searches of the parameters, the restart states fitted again before each
PASSES = 8
#: evaluations of the first search, from the guess's restart states (:func:`diagnosis.fit._search`)
FIRST_PASS = 5
#: ... until a search moves no scaled parameter by more than this (relative) share
SETTLED = 1e-3


def training_plan(judge, part) -> SegmentPlan | None:
    """The segments the training part `part` is fitted on under `judge`: as long as the held-out
    segments, with as many estimation samples; None (open-loop fits) unless the judge chose
    segments for a nominal's unstable mode (:attr:`Judge.unstable
    <diagnosis.segments.Judge.unstable>`), or where `part` holds fewer than two of them."""
    if judge is None or judge.kind != "segments" or not judge.unstable:
        return None
    length, est = judge.plan.length, judge.plan.estimation
    k = part.t.size // max(length, 1)
    if k < 2 or est >= length:
        return None
    return SegmentPlan(tuple(i * length for i in range(k)), length, est, float(part.t[length] - part.t[0]),
                       part.t.size)


def fitted_from(judge, part, start: str) -> str:
    """What the fits on `part` start from, in words: `start` (the recording's initial state as
    described), or the restarted segments of :func:`training_plan`."""
    plan = training_plan(judge, part)
    if plan is None:
        return start
    return (f"states fitted to the data every {plan.seconds:.3g} s ({len(plan.starts)} segments, as the held-out "
            f"judge cuts its part; each restarted from a state fitted to its first {plan.estimation} samples and "
            "scored on the rest, diagnosis.shooting)")


class Shooting:
    """The training part cut into restarted segments (see the module docstring).

    Parameters
    ----------
    sim : OutputSimulator
        The candidate's model on the training part.
    part : Experiment
        The training part.
    plan : SegmentPlan
        The segments: their length and estimation samples follow the held-out judge's.
    noise : dict str -> float
        Noise standard deviation per output (model units).
    nominal_states : tuple of str, optional
        The plant's states (:func:`~diagnosis.restarts.restart_states`).
    """

    def __init__(self, sim, part, plan: SegmentPlan, noise: dict, nominal_states=None):
        self.sim, self.part, self.plan, self.noise = sim, part, plan, dict(noise)
        self.nominal_states = nominal_states
        self.outputs = list(sim.output_names)
        self.measured = {o: np.asarray(part.outputs[o], float) for o in self.outputs}
        self._sims = [sim.on(part.samples(a, b)) for a, b in plan.bounds()]
        self.states = None

    @classmethod
    def for_judge(cls, judge, sim, part):
        """The shooting of `part` under `judge`, or None (:func:`training_plan`)."""
        plan = training_plan(judge, part)
        return None if plan is None else cls(sim, part, plan, judge.noise, judge.nominal_states)

    def restart(self, params, x0) -> None:
        """Fit every segment's restart state at `params`, started from and pulled towards the
        states the last restart fitted, or at the first the model's open-loop run from `x0` where
        it runs (else its default state), and each segment's sensitivity to its restart state
        there (:meth:`__call__`)."""
        try:
            prior = self.sim.run(params, x0).states
        except BondcosimError:
            prior = None
        starts = restart_states(self.sim, self.part, self.plan, self.noise, params, prior, self.nominal_states,
                                starts=self.states, chained=True)
        default = self.sim.initial_state(None)
        self.states = [default if x is None else x for x, _ in starts]
        spread = state_spread(prior, default.size)
        free = [i for i in range(default.size) if i not in carried_states(self.sim, self.nominal_states)]
        self._sensitivity = [self._state_sensitivity(sim, params, x, spread, free)
                             for sim, x in zip(self._sims, self.states)]

    def _state_sensitivity(self, sim, params, x, spread, free):
        """Noise-weighted outputs of one segment per unit change of each free state (forward
        differences; columns of zeros for the states a restart carries), or None where it does
        not run."""
        try:
            base = self._stacked(sim(params, x))
            cols = np.zeros((base.size, x.size))
            for i in free:
                h = _STATE_STEP * max(abs(float(x[i])), float(spread[i]), 1e-12)
                moved = np.array(x, dtype=float)
                moved[i] += h
                cols[:, i] = (self._stacked(sim(params, moved)) - base) / h
        except BondcosimError:
            return None
        return cols if np.isfinite(cols).all() else None

    def _stacked(self, y) -> np.ndarray:
        """The outputs of one segment, each over its noise, one column after the other."""
        return np.concatenate([np.asarray(y[o], float) / max(self.noise.get(o, 0.0), 1e-300) for o in self.outputs])

    def __call__(self, params) -> dict:
        """Outputs on the training part's grid at `params`: on each segment's scored samples, its
        simulation from its restart state moved by the change :math:`\\delta` that the
        noise-weighted least squares of its estimation samples asks for at `params`, to first
        order, :math:`y(x_k + \\delta) \\approx y(x_k) + S_k \\delta` (:math:`S_k` the segment's
        sensitivity to its state, from :meth:`restart`); the measured values on its estimation
        samples (no residual there).  So the restart states follow the parameters while they
        move, as a restart at every evaluation would, to first order, at the cost of one
        simulation: held fixed, they would keep what the guess's model made of the estimation
        samples (a pendulum's speed estimated without its drag) and hold the fit near the guess.
        Raises BondcosimError where a segment does not run."""
        if self.states is None:
            raise BondcosimError("the segments' restart states are not fitted yet (Shooting.restart)")
        out = {o: y.copy() for o, y in self.measured.items()}
        e = self.plan.estimation
        for (a, b), sim, x, S in zip(self.plan.bounds(), self._sims, self.states, self._sensitivity):
            y = sim(params, x)
            if S is not None:
                n = b - a
                est = np.concatenate([np.arange(k * n, k * n + e) for k in range(len(self.outputs))])
                r = self._stacked({o: self.measured[o][a:b] - y[o] for o in self.outputs})[est]
                delta = np.linalg.lstsq(S[est], r, rcond=1e-10)[0]
                moved = S @ delta
                y = {o: y[o] + moved[k * n:(k + 1) * n] * max(self.noise.get(o, 0.0), 1e-300)
                     for k, o in enumerate(self.outputs)}
            for o in self.outputs:
                out[o][a + e:b] = y[o][e:]
        return out
