"""When the held-out part cannot judge: candidates whose effect the held-out part never shows.

The held-out part judges a candidate only where the candidate predicts something different
there.  An effect that acts in a regime the held-out part never reaches (a sensor that clips
at a level the last 30 % of the record stays away from, an end stop hit twice in the first
minute) changes the prediction of the held-out part by less than the noise: the held-out
error can neither confirm nor refute it, and :func:`diagnosis.fit.choose` answers "none"
although the training part shows the effect plainly.

:func:`choose_on_training` is the fallback for that case, and only for it.  A fit is
*silent on the held-out part* when, on every output, its held-out prediction differs from
the nominal one by less than the noise (rms of the difference below one noise standard
deviation, :func:`holdout_change`); a fit that changes the held-out prediction is judged
there, by :func:`~diagnosis.fit.choose`, and never here.  Among the silent fits, the one with
the best training score (the held-out rule's excess error and parameter price, on the
training part) is accepted when

* the nominal training error needs explaining (its excess over the noise floor counts, as in
  rule 1 of :func:`~diagnosis.fit.choose`);
* it explains at least :data:`MIN_TRAIN_SHARE` (50 %) of the nominal training excess error
  (more than the held-out rule's 30 %: the training part also fitted it);
* the drop of its training sum of squares, in noise variances, is at least
  :data:`EVIDENCE_PER_PARAMETER` (Bayesian information criterion's ``ln n``, at least 10) per
  fitted parameter: chance fits of noise do not pass;
* where more than half of that drop lies in the first :data:`START_SHARE` (5 %) of the training
  part, an effect seen only at the start may as well be a wrong initial state: the fit's drop
  there must then exceed, by the same :data:`EVIDENCE_PER_PARAMETER` per parameter, the drop the
  nominal model gains there from a start state re-estimated on those samples
  (:func:`restart_evidence`; without that comparison such a fit is not accepted).  A sensor that
  clipped for the first seconds while the model's level rose is not a different start: no start
  state keeps the model flat there.

The report says when the training part judged (:attr:`CandidateFit.extra` ``"judge"``).
"""
from __future__ import annotations

import numpy as np

__all__ = ["holdout_change", "mark_silent", "choose_on_training", "evidence_drop", "restart_evidence",
           "start_samples", "MIN_TRAIN_SHARE", "EVIDENCE_PER_PARAMETER", "START_SHARE"]

#: Share of the nominal training excess error a training-judged fit must explain.
MIN_TRAIN_SHARE = 0.5
#: Least drop of the training sum of squares, in noise variances, per fitted parameter.
EVIDENCE_PER_PARAMETER = 10.0
#: The start of the training part, as a share of it, that may not hold most of the evidence.
START_SHARE = 0.05


def holdout_change(y_fit: dict, y_nominal: dict, sigma: dict) -> float:
    """The largest, over outputs, rms difference between two held-out predictions in noise
    standard deviations (``inf`` when a prediction is missing or not finite).  Samples neither
    prediction scores (NaN in both: a segment judge's start-estimation samples) are left out."""
    worst = 0.0
    for o, ref in y_nominal.items():
        y = y_fit.get(o) if y_fit else None
        if y is None or sigma.get(o, 0.0) <= 0:
            return float("inf")
        y, ref = np.asarray(y, float), np.asarray(ref, float)
        scored = ~(np.isnan(y) & np.isnan(ref))
        d = y[scored] - ref[scored]
        if d.size == 0 or not np.all(np.isfinite(d)):
            return float("inf")
        worst = max(worst, float(np.sqrt(np.mean(d ** 2))) / sigma[o])
    return worst


def start_samples(n_train: int) -> int:
    """The samples at the start of a training part of `n_train` samples (:data:`START_SHARE`)."""
    return max(1, int(START_SHARE * n_train))


def evidence_drop(y: dict, nominal_y: dict, measured: dict, sigma: dict, n: int) -> np.ndarray:
    """Per sample of the first `n`, the drop of the noise-weighted squared error of prediction `y`
    against the nominal prediction, summed over the outputs with a noise estimate."""
    drop = np.zeros(n)
    for o, ref in nominal_y.items():
        if sigma.get(o, 0.0) <= 0:
            continue
        m = np.asarray(measured[o][:n], float)
        drop += ((m - np.asarray(ref[:n], float)) ** 2 - (m - np.asarray(y[o][:n], float)) ** 2) / sigma[o] ** 2
    return drop


def restart_evidence(sim, train, nominal_y: dict, sigma: dict) -> float:
    """The drop of the noise-weighted squared error over the first :func:`start_samples` samples of
    `train` that the nominal model (`sim`, an OutputSimulator) gains from a start state fitted to
    them (:func:`~diagnosis.initial_state.estimate_initial_state`): what a wrong initial state
    would explain there.  0 when no start state does better (or a restart does not run)."""
    from .errors import BondcosimError
    from .initial_state import estimate_initial_state
    n = start_samples(train.t.size)
    head = train.samples(0, max(n, 2))
    try:
        est = estimate_initial_state(sim.on(head), head, sigma)
        if not est.samples:
            return 0.0
        y = sim.on(head)(None, est.values)
    except BondcosimError:
        return 0.0
    drop = evidence_drop(y, {o: v[:n] for o, v in nominal_y.items()}, head.outputs, sigma, n)
    total = float(np.sum(drop))
    return max(total, 0.0) if np.isfinite(total) else 0.0


def mark_silent(fits, nominal_y: dict, measured: dict, sigma: dict, n_train: int, held_nominal=None) -> None:
    """Record, on each fit with a prediction (``fit.y``, training then held-out samples), its
    held-out change against the nominal prediction `nominal_y` (same samples) in noise
    standard deviations (``extra["holdout_change"]``) and, for the training part, the drop of
    the noise-weighted sum of squares against the nominal (``extra["train_evidence"]``) and
    the share of it in the first :data:`START_SHARE` of the part (``extra["start_share"]``).
    The prediction is then dropped (it is large and used nowhere else).

    `held_nominal` (under the segment judge): the nominal's held-out prediction as that judge
    scores it (:attr:`diagnosis.segments.Judged.segments`), compared with each fit's
    (``extra["holdout_y"]``) instead of the open-loop runs' held-out samples."""
    n_start = start_samples(n_train)
    for fit in fits:
        y = getattr(fit, "y", None)
        if not y:
            continue
        if held_nominal is None:
            held, reference = {o: y[o][n_train:] for o in nominal_y}, {o: v[n_train:] for o, v in nominal_y.items()}
        else:
            held, reference = fit.extra.get("holdout_y"), held_nominal
        fit.extra["holdout_change"] = holdout_change(held, reference, sigma)
        drop = evidence_drop(y, nominal_y, measured, sigma, n_train)
        total = float(np.sum(drop)) if np.all(np.isfinite(drop)) else float("-inf")
        fit.extra["train_evidence"] = total
        fit.extra["start_share"] = float(np.sum(drop[:n_start]) / total) if total > 0 else 1.0
        fit.y = None


def choose_on_training(nominal_train: dict, fits, *, floor: dict, n_train: int, restart=None):
    """The training part's answer among the fits silent on the held-out part, or None.

    Parameters
    ----------
    nominal_train : dict str -> float
        Training NRMSE of the nominal model per output.
    fits : iterable of CandidateFit
        With ``extra`` marked by :func:`mark_silent`.
    floor : dict str -> float
        The training part's noise floor per output (NRMSE), :func:`diagnosis.fit.noise_floor`.
    n_train : int
        Training samples (the information criterion's ``n``).
    restart : callable, optional
        ``restart() -> float``, :func:`restart_evidence` of the nominal model, asked for only when
        the best fit's evidence lies mostly at the start; without it such a fit is not accepted.

    Returns
    -------
    CandidateFit or None
        With ``extra["judge"] = "training"`` and ``extra["train_share"]``.
    """
    from .fit import PARAMETER_PRICE, excess_error, needs_explaining, usable_fits
    significant = needs_explaining(nominal_train, floor)
    if not significant:
        return None
    e0 = excess_error(nominal_train, floor, significant)
    if not np.isfinite(e0) or e0 <= 0:
        return None
    per_parameter = max(EVIDENCE_PER_PARAMETER, float(np.log(max(n_train, 2))))
    names = list(nominal_train)
    silent = [f for f in usable_fits(fits, names) if f.candidate is not None
              and f.extra.get("holdout_change", np.inf) < 1.0
              and all(np.isfinite(f.train_nrmse.get(o, np.nan)) for o in names)]

    def score(f):
        return (excess_error(f.train_nrmse, floor, significant) + 1e-4 * e0) * (1 + PARAMETER_PRICE) ** f.n_params

    if not silent:
        return None
    best = min(silent, key=score)   # only the best may answer: a worse fit is not preferred for passing
    share = 1.0 - excess_error(best.train_nrmse, floor, significant) / e0
    needed = per_parameter * max(best.n_params, 1)
    evidence = best.extra.get("train_evidence", 0.0)
    if share < MIN_TRAIN_SHARE or evidence < needed:
        return None
    at_start = best.extra.get("start_share", 1.0)
    if at_start > 0.5:
        if restart is None:
            return None
        beyond = evidence * at_start - restart()
        best.extra["beyond_restart"] = float(beyond)
        if beyond < needed:
            return None
    best.extra["judge"] = "training"
    best.extra["train_share"] = float(share)
    return best
