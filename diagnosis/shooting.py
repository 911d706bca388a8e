"""Fitting by the segment judge's own error: multiple shooting on the training part.

Under the segment judge (:mod:`diagnosis.segments`: the nominal model drifts or diverges) a
candidate is judged by how well it predicts short segments of the held-out part, each restarted
from a state fitted to its first samples.  Fitted open-loop over the whole training part
instead, from the recording's first state, its training error is whatever the accumulated
drift of the whole run makes it: where the plant is sensitive to its state (a pendulum driven
over the top: a change of a thousandth in a friction level puts it a turn behind within
seconds) even the true law fits no better than the nominal, and the search has no slope to
follow.  So here the training part is cut the way the judge cuts the held-out part
(:class:`Shooting`): segments of the judge's length, each restarted from a state fitted to its
first samples (:func:`diagnosis.segments.restart_states`), scored on the rest.

The restart states are held fixed while the parameters move (the objective is then one
simulation of each segment per evaluation, smooth in the parameters) and are fitted again
at the parameters found; the search then runs once more from there (:data:`PASSES`): a
variable-projection scheme whose states follow the model being fitted.
"""
from __future__ import annotations

import numpy as np

from .errors import BondcosimError
from .segments import SegmentPlan, restart_states

__all__ = ["Shooting", "training_plan", "fitted_from", "PASSES", "SETTLED"]

#: at most this many searches of the parameters, the restart states fitted again before each
PASSES = 8
#: ... until a search moves no scaled parameter by more than this (relative) share
SETTLED = 1e-3


def training_plan(judge, part) -> SegmentPlan | None:
    """The segments the training part `part` is fitted on under `judge`: as long as the held-out
    segments, with as many estimation samples; None under the open-loop judge, or where `part`
    holds fewer than two of them."""
    if judge is None or judge.kind != "segments":
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
        The plant's states (:func:`~diagnosis.segments.restart_states`).
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
        """Fit every segment's restart state at `params`, pulled towards the model's open-loop
        run from `x0` where it runs (else towards its default state)."""
        try:
            prior = self.sim.run(params, x0).states
        except BondcosimError:
            prior = None
        starts = restart_states(self.sim, self.part, self.plan, self.noise, params, prior, self.nominal_states)
        default = self.sim.initial_state(None)
        self.states = [default if x is None else x for x, _ in starts]

    def __call__(self, params) -> dict:
        """Outputs on the training part's grid: each segment simulated at `params` from its restart
        state on its scored samples, the measured values on its estimation samples (no residual
        there).  Raises BondcosimError where a segment does not run."""
        if self.states is None:
            raise BondcosimError("the segments' restart states are not fitted yet (Shooting.restart)")
        out = {o: y.copy() for o, y in self.measured.items()}
        e = self.plan.estimation
        for (a, b), sim, x in zip(self.plan.bounds(), self._sims, self.states):
            y = sim(params, x)
            for o in self.outputs:
                out[o][a + e:b] = y[o][e:]
        return out
