"""The held-out judge: one open-loop simulation, or the segment simulation error where the
nominal model drifts or diverges.

**Open-loop** (the default): the model is simulated from the recording's initial state through
the training part into the held-out part, and its NRMSE there is the judge.  A model that
integrates what it leaves out (a force-driven mass: its position integrates every force error;
a tank without outflow) makes that number mostly accumulated drift, metres of it, and a
diverging one leaves no number at all.  So there the judge is

**the segment simulation error** (multiple shooting on the held-out part): the held-out part is
cut into ``K = min(SEGMENTS, n // MIN_SEGMENT_SAMPLES)`` equal segments (at least one; 5 of 120
samples each on a 3 s, 200 Hz held-out part).  Each segment's state is fitted to its first
half (:data:`ESTIMATION_SHARE`, at least :data:`MIN_ESTIMATION_SAMPLES`, at most
:data:`MAX_ESTIMATION_SAMPLES` samples) by :func:`diagnosis.initial_state.fit_state` (the
noise-weighted least squares of the initial state, pulled weakly towards the state the model's
open-loop run has there when that is finite, else towards the model's default), the segment is
simulated from that state, and the error on its remaining samples is pooled over the segments,
with its own noise floor (:meth:`Judge.segment_error`),

.. math:: \\mathrm{NRMSE}_o = \\sqrt{\\tfrac1N \\textstyle\\sum_k \\sum_{i \\in k,\\,\\mathrm{scored}}
          (y_{o,i} - \\hat y_{o,i})^2} \\,/\\, \\mathrm{std}(y_o \\text{ on the held-out part}).

A segment whose simulation leaves the finite numbers counts as predicting the held-out mean.
Every model (the nominal and each candidate, with its own added states) is judged the same
way, so the nominal reference and the candidates' numbers stay comparable.  Only a state a
candidate adds that follows the inputs alone (an actuator's lag: :func:`input_driven_states`)
is not fitted at a restart: it continues from the candidate's own run, which has it exactly.
This is the benchmark's convention for a drifting plant (:mod:`diagnosis.benchmark.draw` sizes an
effect with the nominal restarted from the truth's state every tenth of the record).

**The rule** (:func:`choose_judge`): segments when

1. the nominal model diverges on the recording, or
2. it drifts: it has a mode that integrates what it leaves out (:func:`drifting_mode`: an
   eigenvalue of :math:`\\partial f/\\partial x` at one of five points of its run that neither
   decays nor turns within the held-out part, real part above :math:`-1/(10\\,T_{held})` and
   imaginary part below :math:`2\\pi/T_{held}`, or grows by e within it: an integrator, a slow or
   unstable mode; not an undamped oscillation), **and** on some output that needs
   explaining its open-loop held-out error, less what an output offset and gain fitted on the
   training part explain (when they lower it), is more than :data:`DRIFT_RATIO` (2) times its
   segment NRMSE: restarting from the data removes most of its error, so that error is
   accumulated drift, not a wrong response.  (A restart absorbs a sensor's offset or gain too, which is no drift and
   persists from the training part into the held-out part: a carriage whose position sensor
   reads 10 % high keeps the open-loop judge.)
3. or its mode grows e-fold within the held-out part and its open-loop prediction there is
   chaotic (:func:`chaotic_spread`): started :data:`CHAOS_NUDGE` of each state's range away, the
   nominal's held-out outputs end more than one noise standard deviation apart, so a candidate's
   change of the model moves its open-loop error by chance.  Under such a judge the training
   part does not answer either (:mod:`diagnosis.training_judge`).

Otherwise open-loop stays the judge (a stable plant, or an integrating one whose nominal does
not drift on this recording, such as a carriage whose velocity sensor reads off).

The segment length is a stated default, not read from the dynamics: an integrator has no time
constant to follow; a half of each segment for its state keeps the restarted velocity's noise
small against the effect the scored half is to show.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import BondcosimError
from .restarts import SegmentPlan, input_driven_states, restart_states

__all__ = ["SegmentPlan", "Judged", "Judge", "plan_segments", "choose_judge", "drifting_mode", "grows_within",
           "input_driven_states", "SEGMENTS", "UNSTABLE_HORIZON", "MIN_SEGMENT_SAMPLES", "ESTIMATION_SHARE",
           "MIN_ESTIMATION_SAMPLES", "MAX_ESTIMATION_SAMPLES", "DRIFT_RATIO", "SLOW_MODE", "FLOOR_MARGIN",
           "CHAOS_NUDGE", "chaotic_spread"]

#: segments the held-out part is cut into (fewer when it is short)
SEGMENTS = 5
#: e-foldings of a nominal's unstable mode a segment's scored half spans at most (:func:`plan_segments`)
UNSTABLE_HORIZON = 2.0
#: fewest samples of a segment
MIN_SEGMENT_SAMPLES = 40
#: share of each segment whose samples estimate its state (not scored)
ESTIMATION_SHARE = 0.5
MIN_ESTIMATION_SAMPLES, MAX_ESTIMATION_SAMPLES = 10, 200
#: open-loop / segment NRMSE of the nominal above which its error counts as drift
DRIFT_RATIO = 2.0
#: a mode whose time constant exceeds this many held-out spans does not decay
SLOW_MODE = 10.0
#: relative start-state nudge (of each state's range over the run) that tells a chaotic nominal (:func:`chaotic_spread`)
CHAOS_NUDGE = 1e-6
#: the segment error's noise floor is known only roughly (a noise estimate that quantisation
#: can fool, a linearised propagation of the restarts' state noise): an output counts as
#: unexplained only beyond this multiple of it
FLOOR_MARGIN = 1.5


def plan_segments(held, growth: float | None = None) -> SegmentPlan:
    """The segments of the held-out part `held` (an Experiment; see the module docstring).

    With `growth` (1/s), the growth rate of a nominal's unstable mode, the segments are no longer
    than :data:`UNSTABLE_HORIZON` e-foldings scored after as long an estimation (and as many as
    fit): a chaotic Duffing oscillator's error grows e-fold every 1.6 s, so five segments of 12 s
    predicted garbage restarted or not, and the judge took its drift for a wrong response."""
    n = held.t.size
    k = int(max(1, min(SEGMENTS, n // MIN_SEGMENT_SAMPLES)))
    length = n // k
    if growth is not None and growth > 0 and n > 1:
        dt = float(held.t[-1] - held.t[0]) / (n - 1)
        short = max(MIN_SEGMENT_SAMPLES, int(round(2 * UNSTABLE_HORIZON / (growth * dt))))
        if short < length:
            k, length = max(1, n // short), short
    est = int(np.clip(round(ESTIMATION_SHARE * length), MIN_ESTIMATION_SAMPLES, MAX_ESTIMATION_SAMPLES))
    est = min(est, max(length - 2, 1))
    seconds = float(held.t[min(length, n - 1)] - held.t[0]) if n > 1 else 0.0
    return SegmentPlan(tuple(i * length for i in range(k)), length, est, seconds, n)


@dataclass
class Judged:
    """One model judged on the held-out part.

    Attributes
    ----------
    nrmse : dict str -> float
        The judge's held-out NRMSE per output (the segment error under the segment judge).
    open_loop : dict str -> float
        The open-loop held-out NRMSE (inf when the run diverged).
    y : dict str -> ndarray
        Open-loop outputs on the whole grid (NaN when the run diverged).
    segments : dict str -> ndarray or None
        Segment simulations on the held-out part (NaN on the estimation samples and between
        segments), None under the open-loop judge.
    states : ndarray or None
        Open-loop states on the whole grid (None when the run diverged).
    floor : dict str -> float or None
        The segment judge's noise floor as an NRMSE, when asked for (:meth:`Judge.evaluate`).
    """

    nrmse: dict
    open_loop: dict
    y: dict
    segments: dict | None = None
    states: np.ndarray | None = None
    floor: dict | None = None


def _nrmse(y, yhat):
    spread = float(np.std(y)) or 1.0
    return float(np.sqrt(np.mean((y - yhat) ** 2)) / spread)


@dataclass
class Judge:
    """How held-out errors are measured in one diagnosis.

    Attributes
    ----------
    kind : str
        ``"open-loop"`` or ``"segments"``.
    reason : str
        Why, in words.
    held : Experiment
        The held-out part (the last ``held.t.size`` samples of every simulated grid).
    noise : dict str -> float
        Noise standard deviation per output (model units), weights of the state estimates.
    plan : SegmentPlan
    floor : dict str -> float or None
        The noise floor of the segment error (an NRMSE per output), set by :func:`choose_judge`.
    nominal_states : tuple of str or None
        The nominal model's states: a candidate's other states are its own (an actuator's lag).
        None: every state is the plant's (none is carried through a restart).
    mode : complex or None
        The nominal's drifting mode (:func:`drifting_mode`, 1/s) where the judge chose segments
        for it; None otherwise.
    """

    kind: str
    reason: str
    held: object
    noise: dict
    plan: SegmentPlan
    floor: dict | None = None
    nominal_states: tuple | None = None
    mode: complex | None = None

    @property
    def unstable(self) -> bool:
        """Whether the nominal's drifting mode grows by e or more within the held-out part (an
        unstable mode, as a pendulum's over the top: an error grows exponentially), not an
        integrator's or a slow mode's (a force-driven carriage: an error accumulates, its effect
        on the whole run smooth in the parameters)."""
        span = float(self.held.t[-1] - self.held.t[0]) if self.held.t.size > 1 else 0.0
        return grows_within(self.mode, span)

    def evaluate(self, sim, params=None, x0=None, *, floor=False) -> Judged:
        """Judge the model of `sim` (an OutputSimulator on the whole grid, whose last
        ``held.t.size`` samples are the held-out part) with parameters `params` from `x0`;
        with `floor`, also the segment error's noise floor for this model (:meth:`segment_error`)."""
        n_held = self.held.t.size
        outputs = list(sim.output_names)
        try:
            run = sim.run(params, x0)
            y, states = run.outputs, run.states
            open_loop = {o: _nrmse(self.held.outputs[o], y[o][-n_held:]) for o in outputs}
        except BondcosimError:
            y = {o: np.full(sim.t.size, np.nan) for o in outputs}
            states, open_loop = None, {o: float("inf") for o in outputs}
        if self.kind != "segments":
            return Judged(dict(open_loop), open_loop, y, None, states)
        prior = None if states is None else states[-n_held:]
        nrmse, seg, noise_floor = self.segment_error(sim, params, prior, floor=floor)
        return Judged(nrmse, open_loop, y, seg, states, noise_floor)

    def segment_error(self, sim, params=None, prior=None, *, floor=False):
        """``(nrmse, outputs, floor)`` of the segment simulations (module docstring); `prior`:
        states on the held-out part to pull each segment's estimate towards (None: the model's
        default).

        With `floor`, the error the procedure leaves for this model if it were right: the
        measurement noise plus the noise of each segment's estimated state carried into its
        scored samples, :math:`\\nu_o^2 = (\\sigma_o^2 + \\overline{\\mathrm{diag}(S P S^T)}) /
        \\mathrm{std}(y_o)^2`, with :math:`P` the estimate's covariance
        (:func:`~diagnosis.initial_state.fit_state`) and :math:`S` the scored outputs'
        sensitivity to the state (differences over one standard deviation of each state), times
        :data:`FLOOR_MARGIN`; otherwise None.  The measurement noise alone would understate it: a
        velocity estimated from a few noisy positions carries its error into every later position."""
        held, plan = self.held, self.plan
        outputs = list(sim.output_names)
        sq = {o: 0.0 for o in outputs}
        spread_var = {o: 0.0 for o in outputs}
        count = 0
        seg = {o: np.full(held.t.size, np.nan) for o in outputs}
        starts = restart_states(sim, held, plan, self.noise, params, prior, self.nominal_states, covariance=True,
                                chained=self.unstable)
        for (a, b), (x, cov) in zip(plan.bounds(), starts):
            e = a + plan.estimation
            seg_sim = sim.on(held.samples(a, b))
            try:
                if x is None:
                    raise BondcosimError("no state fits the segment's first samples")
                out = seg_sim(params, x)
                if not all(np.isfinite(out[o]).all() for o in outputs):
                    raise BondcosimError("non-finite outputs")
                if floor:
                    for o, v in _carried_variance(seg_sim, params, x, cov, out, e - a).items():
                        spread_var[o] += v
            except BondcosimError:           # a diverging segment predicts the held-out mean
                out = {o: np.full(b - a, float(np.mean(held.outputs[o]))) for o in outputs}
            for o in outputs:
                r = np.asarray(held.outputs[o][e:b], float) - out[o][e - a:]
                sq[o] += float(r @ r)
                seg[o][e:b] = out[o][e - a:]
            count += b - e
        std = {o: float(np.std(held.outputs[o])) or 1.0 for o in outputs}
        nrmse = {o: float(np.sqrt(sq[o] / max(count, 1)) / std[o]) for o in outputs}
        noise_floor = ({o: FLOOR_MARGIN * float(np.sqrt(self.noise.get(o, 0.0) ** 2 + spread_var[o] / max(count, 1)))
                        / std[o] for o in outputs} if floor else None)
        return nrmse, seg, noise_floor

    def to_json(self) -> dict:
        out = {"judge": self.kind, "judge_reason": self.reason}
        if self.kind == "segments":
            out["segments"] = self.plan.to_json()
        return out


def _carried_variance(seg_sim, params, x, cov, out, first) -> dict:
    """Sum over the scored samples (from `first` on) of each output's variance carried from the
    estimated state's covariance `cov` (one run per state, displaced by its standard deviation)."""
    outputs = list(out)
    total = {o: 0.0 for o in outputs}
    if cov is None or not np.isfinite(cov).all() or not x.size:
        return total
    sd = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    cols = {o: [] for o in outputs}
    for i in range(x.size):
        if sd[i] <= 0:
            for o in outputs:
                cols[o].append(np.zeros(out[o].size - first))
            continue
        moved = x.copy()
        moved[i] += sd[i]
        y = seg_sim(params, moved)
        for o in outputs:
            cols[o].append((y[o][first:] - out[o][first:]) / sd[i])
    for o in outputs:
        S = np.column_stack(cols[o])
        var = np.einsum("ki,ij,kj->k", S, cov, S)
        total[o] = float(np.sum(np.where(np.isfinite(var), var, 0.0)))
    return total


def grows_within(mode, span: float) -> bool:
    """Whether the eigenvalue `mode` (1/s, or None) grows by e or more within `span` seconds."""
    return mode is not None and mode.real * span > 1.0


def chaotic_spread(sim, run, n_held: int, noise: dict) -> float:
    """How far apart, on the last `n_held` samples, the outputs of `sim` end when its `run` is
    started :data:`CHAOS_NUDGE` of each state's range away: the largest rms difference over the
    outputs, in noise standard deviations (``inf`` when the nudged run fails).  Above 1 the
    open-loop prediction is chaotic: a candidate's tiny change of the model (a constant load of
    1.7e-8 N on a double-well Duffing oscillator's nominal, the right model) reshuffles it, and
    its held-out error then falls or rises by chance."""
    from .training_judge import holdout_change
    states = np.asarray(run.states, float)
    if not states.size or not np.isfinite(states).all():
        return float("inf")
    span = np.ptp(states, axis=0)
    nudge = CHAOS_NUDGE * np.where(span > 0, span, np.maximum(np.abs(states[0]), 1.0))
    try:
        y = sim.run(None, states[0] + nudge).outputs
    except BondcosimError:
        return float("inf")
    sensed = [o for o in run.outputs if noise.get(o, 0.0) > 0]
    return holdout_change({o: y[o][-n_held:] for o in sensed}, {o: run.outputs[o][-n_held:] for o in sensed}, noise)


def _segment_floor(judge, sim, run, judged) -> dict:
    """The segment judge's noise floor: `judged`'s (linearised), and for a nominal with an unstable
    mode no lower than the replayed one (:func:`_replayed_floor`)."""
    if not judge.unstable:
        return judged.floor
    replayed = _replayed_floor(judge, sim, run.states[-judge.held.t.size:])
    return {o: max(v, replayed[o]) for o, v in judged.floor.items()}


def _replayed_floor(judge, sim, prior, seed: int = 0) -> dict:
    """The segment error's floor for a nominal with an unstable mode, replayed: the held-out part
    made again by the nominal itself (each segment simulated whole from its restart state, plus
    Gaussian noise of each output's level), judged as the recording is, times
    :data:`FLOOR_MARGIN`.  The linearised floor (:meth:`Judge.segment_error`) understates what a
    restart's noise grows to across two e-foldings of a chaotic oscillator: the right model of a
    double-well Duffing oscillator left 0.016 on its recording, above its linearised floor of 0.012
    (replayed: 0.032), and a constant load of 0.0005 N, no physics at all, passed as an effect."""
    from dataclasses import replace
    held, plan = judge.held, judge.plan
    rng = np.random.default_rng(seed)
    made = {o: np.asarray(v, float).copy() for o, v in held.outputs.items()}
    starts = restart_states(sim, held, plan, judge.noise, None, prior, judge.nominal_states, chained=True)
    for (a, b), (x, _) in zip(plan.bounds(), starts):
        try:
            if x is None:
                continue
            y = sim.on(held.samples(a, b))(None, x)
        except BondcosimError:
            continue
        for o in made:
            if np.isfinite(y[o]).all():
                made[o][a:b] = y[o] + rng.normal(0.0, judge.noise.get(o, 0.0), b - a)
    again = replace(judge, held=replace(held, outputs=made), floor=None)
    nrmse = again.segment_error(sim, None, prior)[0]
    return {o: FLOOR_MARGIN * v for o, v in nrmse.items()}


def _beyond_sensor(y, y_hat, n_held) -> float:
    """Held-out NRMSE of the open-loop residual ``y - y_hat`` (whole record, the last `n_held`
    samples held out) left by an output offset and gain ``a + b y_hat`` fitted on the training
    part: a restart absorbs a sensor's error as well as a drift, but only a sensor's error
    persists from the training part into the held-out part with the same offset and gain."""
    y, y_hat = np.asarray(y, float), np.asarray(y_hat, float)
    if not np.isfinite(y_hat).all():
        return float("inf")
    basis = np.column_stack([np.ones_like(y_hat), y_hat])
    r = y - y_hat
    coef, *_ = np.linalg.lstsq(basis[:-n_held], r[:-n_held], rcond=None)
    left = r[-n_held:] - basis[-n_held:] @ coef
    return float(np.sqrt(np.mean(left ** 2)) / (float(np.std(y[-n_held:])) or 1.0))


def drifting_mode(sim, run, span: float, params=None, points: int = 5):
    """An eigenvalue of :math:`\\partial f/\\partial x` (at `points` samples spread over `run`)
    through which the model integrates what it leaves out, or None.

    Such a mode neither decays nor oscillates within the held-out part of `span` seconds:
    real part above :math:`-1/(10\\,T)` (:data:`SLOW_MODE`) and imaginary part below
    :math:`2\\pi/T` (less than one turn), as a force-driven mass's 0 or a tank's slow outflow;
    or it grows by e within the span (real part above :math:`1/T`).  An undamped oscillation
    (a frictionless joint's spring) is none: a force error shifts it, it does not accumulate.
    Returns the eigenvalue with the largest real part among those (1/s), None when there is none.
    """
    m = sim.model
    n_states = run.states.shape[1]
    if not n_states:
        return None
    p = m.param_vector(params)
    found = None
    for k in np.linspace(0, run.t.size - 1, points).astype(int):
        try:
            J = m.jac_x(run.states[k:k + 1], run.inputs[k:k + 1], t=float(run.t[k]), p=p)
        except (BondcosimError, FloatingPointError, np.linalg.LinAlgError):
            continue
        J = np.asarray(J, float).reshape(n_states, n_states)
        if not np.isfinite(J).all():
            continue
        for lam in np.linalg.eigvals(J):
            slow = lam.real > -1.0 / (SLOW_MODE * span) and abs(lam.imag) < 2 * np.pi / span
            if (slow or lam.real > 1.0 / span) and (found is None or lam.real > found.real):
                found = complex(lam)
    return found


def _eig(lam) -> str:
    return f"{lam.real:.3g} 1/s" if abs(lam.imag) < 1e-12 else f"{lam.real:.3g} {lam.imag:+.3g}j 1/s"


def choose_judge(sim, exp, held, res, diverged: str, floor: dict, x0=None):
    """The judge of this diagnosis and the nominal model judged by it: ``(Judge, Judged)``.

    Parameters
    ----------
    sim : OutputSimulator
        The nominal model on the whole recording `exp`.
    held : Experiment
        The held-out part.
    res : Residuals
        The nominal residuals (noise levels; the run, unless it diverged).
    diverged : str
        Why the nominal simulation diverged, ``""`` if it did not.
    floor : dict str -> float
        Noise floor per output, as an NRMSE (:func:`diagnosis.fit.noise_floor`).
    x0 : dict, optional
        The recording's initial state.
    """
    from .fit import needs_explaining
    span = float(held.t[-1] - held.t[0]) or 1.0
    mode = None if diverged else drifting_mode(sim, res.run, span)
    plan = plan_segments(held, mode.real if grows_within(mode, span) else None)
    segments = Judge("segments", "", held, dict(res.noise), plan, nominal_states=tuple(sim.model.state_names))
    if diverged:
        segments.reason = f"the nominal model diverges on the recording ({diverged})"
        judged = segments.evaluate(sim, None, x0, floor=True)
        segments.floor = judged.floor
        return segments, judged
    if mode is None:
        judge = Judge("open-loop", "every mode of the nominal model decays or oscillates within the held-out "
                      "part (none integrates what the model leaves out)", held, dict(res.noise), plan)
        return judge, judge.evaluate(sim, None, x0)
    judged = segments.evaluate(sim, None, x0, floor=True)
    n_held = held.t.size
    beyond = {o: min(judged.open_loop[o], _beyond_sensor(exp.outputs[o], judged.y[o], n_held))
              for o in judged.open_loop}
    drift = [o for o in needs_explaining(judged.open_loop, floor) if beyond[o] > DRIFT_RATIO * judged.nrmse[o]]
    if drift:
        segments.mode = mode
        what = (f"an unstable mode (eigenvalue {_eig(mode)}: an error grows e-fold every {1 / mode.real:.3g} s)"
                if segments.unstable else f"a mode that integrates what it leaves out (eigenvalue {_eig(mode)})")
        segments.reason = (f"the nominal model has {what} and its open-loop held-out error is mostly drift: "
                           + ", ".join(f"{o} open-loop {judged.open_loop[o]:.3g} ({beyond[o]:.3g} beyond an "
                                       f"output offset and gain) against {judged.nrmse[o]:.3g} restarted "
                                       f"every {plan.seconds:.3g} s" for o in drift))
        segments.floor = _segment_floor(segments, sim, res.run, judged)
        return segments, judged
    spread = chaotic_spread(sim, res.run, n_held, res.noise) if grows_within(mode, span) else 0.0
    if spread > 1.0:
        segments.mode = mode
        segments.reason = (f"the nominal model has an unstable mode (eigenvalue {_eig(mode)}: an error grows e-fold "
                           f"every {1 / mode.real:.3g} s) and its open-loop prediction of the held-out part is "
                           f"chaotic: started {CHAOS_NUDGE:g} of each state's range away, it ends {spread:.3g} "
                           f"noise standard deviations apart (rms), so no open-loop fit can be told from chance")
        segments.floor = _segment_floor(segments, sim, res.run, judged)
        return segments, judged
    judge = Judge("open-loop", f"the nominal model has a mode that integrates what it leaves out (eigenvalue "
                  f"{_eig(mode)}), but restarting it from the data does not remove most of its "
                  f"held-out error (no drift)", held, dict(res.noise), plan)
    return judge, Judged(dict(judged.open_loop), judged.open_loop, judged.y, None, judged.states)
