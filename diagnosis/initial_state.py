"""The state a recording starts in, estimated from its first samples.

A recording rarely starts where the model's default initial state says (a
rig at rest with its valves half open, a tank already filled, an axis that
has been moving): simulated from the default, even the right model is wrong
for the whole settling time and, if it integrates, for ever after.  So the
initial state is fitted first, on a short window at the start of the
recording, by least squares of the outputs' error weighted by their noise,
with a weak pull towards the default state (unobservable states stay at the
default):

.. math::

    \\min_{x_0} \\sum_o \\sum_{k<W} \\Big(\\frac{y_{o,k} - \\hat y_{o,k}(x_0)}{\\sigma_o}\\Big)^2
    + \\lambda^2 \\sum_i \\Big(\\frac{x_{0,i} - \\bar x_{0,i}}{s_i}\\Big)^2

with :math:`s_i` the state's scale (its default's magnitude, or its spread in
the nominal run), :math:`\\lambda` = :data:`PULL` per sample.  The pipeline
(:func:`diagnosis.diagnose.diagnose`) calls it only where the default start
contradicts the data (a decaying transient of the model's own, or a
divergence), so that a persistent effect is not absorbed into the state.  The estimate is
kept only when it lowers the window's error by :data:`MIN_GAIN`; a model that
leaves the finite numbers from its default start is tried on shorter windows.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from .errors import BondcosimError

__all__ = ["InitialState", "estimate_initial_state", "fit_state", "start_inconsistent", "window_length", "PULL",
           "MIN_GAIN", "START_SAMPLES"]

#: weight of the pull towards the default state, relative to one sample of one output at its noise
PULL = 1e-2
#: the estimate must lower the window's weighted squared error by this share to be kept
MIN_GAIN = 0.2


@dataclass(frozen=True)
class InitialState:
    """An estimated initial state.

    Attributes
    ----------
    values : dict str -> float
        State name -> value (SI) at the recording's first sample.
    samples : int
        Length of the window it was fitted on (0: not estimated, the default is kept).
    gain : float
        Share of the window's weighted squared output error the estimate removes.
    description : str
        How the state was obtained, for the report.
    """

    values: dict
    samples: int
    gain: float
    description: str


def window_length(n: int) -> int:
    """Samples of the start window for a training part of `n` samples (5 %, 20-2000)."""
    return int(max(20, min(2000, n // 20)))


def estimate_initial_state(sim, experiment, noise: dict, *, scales=None, params=None, states=None) -> InitialState:
    """Fit the initial state of `sim`'s model to the first samples of `experiment`.

    Parameters
    ----------
    sim : OutputSimulator
        The compiled nominal model (any experiment; it is re-gridded with ``sim.on``).
    experiment : Experiment
        The recording (training part); its first samples are used.
    noise : dict str -> float
        Noise standard deviation of each measured output (model units).
    scales : dict str -> float, optional
        Typical magnitude of each state (default: its default value's magnitude, else 1).
    params : dict str -> float, optional
        Parameter values of the model (SI; default: its own).
    states : iterable of str, optional
        The states fitted (default: all); the others stay at their default values.

    Returns
    -------
    InitialState
    """
    x_def = sim.initial_state(None)
    names = list(sim.model.state_names)
    wanted = None if states is None else set(states)
    free = None if wanted is None else np.array([nm in wanted for nm in names])
    if not names or (free is not None and not free.any()):
        return InitialState(dict(zip(names, map(float, x_def))), 0, 0.0,
                            "the model's initial state (it has no states to fit)")
    s = np.array([abs(v) if v != 0 else 1.0 for v in x_def], float)
    if scales:
        s = np.array([max(float(scales.get(nm, 0.0)), si) for nm, si in zip(names, s)])
    outputs = list(experiment.outputs)
    n = window_length(experiment.t.size)
    while n >= 20:
        part = experiment.window(float(experiment.t[0]), float(experiment.t[min(n, experiment.t.size) - 1]))
        y = {o: np.asarray(part.outputs[o], float) for o in outputs}
        problem = _StateProblem(sim.on(part), y, noise, x_def, s, params, free)
        k = int(problem.free.sum())
        r0 = problem(np.zeros(k))
        if np.all(r0[:-k] < 1e6):
            break
        n //= 2                                   # the default start diverges in the window
    else:
        return InitialState(dict(zip(names, map(float, x_def))), 0, 0.0,
                        "the model's initial state (the model diverges from it at once)")
    size = part.t.size
    cost0 = float(np.sum(r0 ** 2))
    x, cost = problem.solve()
    if x is None:
        return InitialState(dict(zip(names, map(float, x_def))), 0, 0.0, "the model's initial state")
    gain = 1.0 - cost / cost0 if cost0 > 0 else 0.0
    if gain < MIN_GAIN:
        return InitialState(dict(zip(names, map(float, x_def))), 0, gain,
                            f"the model's initial state (fitting it on the first {size} samples gained "
                            f"{100 * max(gain, 0):.0f} %)")
    return InitialState(dict(zip(names, map(float, x))), size, gain,
                        f"a state estimated from the first {size} samples "
                        f"({100 * gain:.0f} % less error there than from the model's initial state)")


class _StateProblem:
    """The weighted least squares of the module docstring on one window: residual vector of
    the scaled state offset ``theta`` of the `free` states (``x = prior + theta * scale`` there;
    the others stay at the prior)."""

    def __init__(self, w_sim, y, noise, prior, scale, params=None, free=None):
        self.sim, self.y, self.prior, self.scale, self.params = w_sim, y, prior, scale, params
        # the states fitted (a mask); the others stay at the prior
        self.free = np.ones(len(prior), dtype=bool) if free is None else np.asarray(free, dtype=bool)
        self.outputs = list(y)
        self.sig = {o: max(float(noise.get(o, 0.0)), 1e-9 * (float(np.std(v)) or 1.0)) for o, v in y.items()}
        self.size = len(next(iter(y.values()))) if y else 0

    def state(self, theta) -> np.ndarray:
        """The state of the free states' scaled offset `theta`."""
        x = self.prior.copy()
        x[self.free] += theta * self.scale[self.free]
        return x

    def __call__(self, theta):
        x = self.state(theta)
        try:
            out = self.sim.run(self.params, x).outputs
        except BondcosimError:
            return np.full(self.size * len(self.outputs) + len(theta), 1e6)
        r = [(self.y[o] - out[o]) / self.sig[o] for o in self.outputs]
        return np.concatenate(r + [PULL * np.sqrt(self.size) * theta])

    def solve(self, with_jacobian=False):
        """``(state, cost)``, cost the weighted sum of squares; ``(None, inf)`` when it fails;
        with `with_jacobian` also the residual's Jacobian in the scaled offset (None on failure)."""
        n = int(self.free.sum())
        if not n:
            r = self(np.zeros(0))
            out = (self.prior.copy(), float(r @ r))
            return out + (np.zeros((r.size, 0)),) if with_jacobian else out
        try:
            fit = least_squares(self, np.zeros(n), method="trf", x_scale=1.0, max_nfev=20 * n + 20,
                                xtol=1e-6, ftol=1e-6)
        except (ValueError, FloatingPointError, np.linalg.LinAlgError):
            fit = None
        if fit is None or not np.all(np.isfinite(fit.x)):
            return (None, np.inf, None) if with_jacobian else (None, np.inf)
        out = (self.state(fit.x), 2.0 * float(fit.cost))
        return out + (np.asarray(fit.jac, dtype=float),) if with_jacobian else out


def fit_state(w_sim, y: dict, noise: dict, prior, scale=None, *, params=None, covariance=False, kept=()):
    """The state at the first sample of a window, fitted to its measured outputs.

    The same noise-weighted least squares with a weak pull towards `prior` as
    :func:`estimate_initial_state`, without its acceptance rule: used to restart a
    simulation from the data (:mod:`diagnosis.segments`).

    Parameters
    ----------
    w_sim : OutputSimulator
        The compiled model on the window's grid and inputs.
    y : dict str -> ndarray
        Measured outputs on the window (model units).
    noise : dict str -> float
        Noise standard deviation of each output (model units).
    prior : array_like, shape (n_states,)
        The state pulled towards (SI), e.g. a simulation's state there or the default.
    scale : array_like, optional
        Typical magnitude of each state (default: the prior's magnitude, else 1).
    params : dict, optional
        Parameter values of the model (SI).
    covariance : bool
        Also return the covariance of the estimate (SI), the Gauss-Newton
        :math:`S (J^T J)^{-1} S` at the solution (:math:`J` the noise-weighted residual's Jacobian,
        :math:`S` the diagonal of `scale`): what the measurement noise leaves uncertain.
    kept : sequence of int
        Indices of states not fitted: they stay at `prior` (their variance is 0).

    Returns
    -------
    ndarray or None
        The fitted state; None when the model cannot run from any tried state.  With
        `covariance`, ``(state, covariance)`` (covariance None when the fit failed).
    """
    prior = np.asarray(prior, dtype=float)
    if not prior.size:
        return (prior, np.zeros((0, 0))) if covariance else prior
    if scale is None:
        scale = np.where(np.abs(prior) > 0, np.abs(prior), 1.0)
    scale = np.asarray(scale, dtype=float)
    free = np.ones(prior.size, dtype=bool)
    free[list(kept)] = False
    problem = _StateProblem(w_sim, y, noise, prior, scale, params, free)
    if not covariance:
        return problem.solve()[0]
    x, _, jac = problem.solve(with_jacobian=True)
    if x is None:
        return None, None
    cov = np.zeros((prior.size, prior.size))
    cov[np.ix_(free, free)] = np.linalg.pinv(jac.T @ jac) * np.outer(scale[free], scale[free])
    return x, cov


def start_inconsistent(res, diverged, n_train) -> bool:
    """Whether the model's default initial state contradicts the recording's start.

    So it is when the nominal simulation diverges, or when both

    * its error over the first samples (the window :mod:`diagnosis.initial_state` fits on)
      is more than twice the error over the rest of the training part on some output: a
      transient of the model's own, which decays; and
    * the outputs disagree at the first sample itself: on some output, the residual's value
      at the start, from a quadratic fitted to its first :data:`START_SAMPLES` samples, is
      more than 4 standard errors (of that noise) from zero.  A missing effort or flow
      acting from the start (a load on a rig at rest) moves the outputs away from the
      model's gradually, from zero; a wrong initial state shows at once.  (A start that
      differs only in unmeasured states shows no jump: it is left to the candidates.)

    An error that persists or grows (an offset, a missing friction) is left to the
    candidates: fitting the start to it would absorb the effect into the state.
    """
    if diverged:
        return True
    w = window_length(n_train)
    if n_train < 2 * w:
        return False
    for o, r in res.residual.items():
        head = float(np.sqrt(np.mean(r[:w] ** 2)))
        rest = float(np.sqrt(np.mean(r[w:n_train] ** 2)))
        if head > 2.0 * rest and _jumps_at_start(r, res.noise.get(o, 0.0)):
            return True
    return False


#: Samples at the start of the recording on which the residual's initial value is estimated.
START_SAMPLES = 20

#: RMS misfit of the quadratic, in noise standard deviations, beyond which the residual's start is
#: too rough for it (white noise alone leaves about 0.9)
_ROUGH = 2.0


def _jumps_at_start(residual, sigma: float) -> bool:
    """Whether `residual` starts away from zero: the intercept of a quadratic least-squares fit
    to its first :data:`START_SAMPLES` samples (in sample units) is more than 4 of its standard
    errors from zero, for white noise of standard deviation `sigma`; where the quadratic leaves
    more than :data:`_ROUGH` sigma, the first sample alone, beyond 4 sigma."""
    k = min(START_SAMPLES, residual.size)
    if k < 4 or sigma <= 0:
        return True
    basis = np.vander(np.arange(k, dtype=float), 3, increasing=True)
    coef, *_ = np.linalg.lstsq(basis, residual[:k], rcond=None)
    misfit = float(np.sqrt(np.mean((basis @ coef - residual[:k]) ** 2)))
    if misfit > _ROUGH * sigma:
        # not smooth over those samples (a load from rest on a 57 Hz oil column rings within
        # them, seed 2727, case 002): the quadratic's intercept is biased, the first sample decides
        return abs(float(residual[0])) > 4.0 * sigma
    se = sigma * float(np.sqrt(np.linalg.inv(basis.T @ basis)[0, 0]))
    return abs(float(coef[0])) > 4.0 * se

