"""Under the segment judge, a fit that predicts the whole held-out part open-loop to the noise.

Where the nominal model integrates what it leaves out, its open-loop held-out error is mostly
drift, and every model is judged by the segment simulation error (:mod:`diagnosis.segments`):
restarted every few tenths of a second from a state fitted to the data, so that stopping the
drift alone earns nothing.  The restarts carry the noise of their estimated states into the
scored samples, and the segment judge's floor is raised by it: on a force-driven carriage a
viscous friction fitted to within 0.2 % of the truth lowered the segment error of the speed from
0.046 to 0.031, inside that floor, and the answer was ``none`` (seed 4747, case 014), although
the fitted model, simulated open-loop from the recording's start, predicts the held-out part as
well as the noise allows (NRMSE 0.032 against the nominal's 1.5).

So, when the segment judge answers ``none``, the fits are judged once more on their open-loop
held-out errors against the nominal's open-loop errors and the measurement noise floor, by the
same rule (:func:`diagnosis.fit.choose`), and the winner is accepted only when it predicts the
held-out part open-loop to within :data:`~diagnosis.fit.NEAR_FLOOR` times that floor (root sum
of squares over the outputs that need explaining).  Stopping the drift is not enough: a Coulomb
friction or a constant load on the same carriage stops it too, with open-loop errors of the speed
three and seven times the viscous law's.  A null recording whose nominal does not drift never
reaches this rule (it is judged open-loop from the start).  It applies to the first round
(:func:`diagnosis.diagnose.diagnose`); further rounds are judged as before.

The fits of other kinds the open-loop held-out part cannot tell apart from the winner are listed
with it, by the same test as under the other judges (:func:`diagnosis.alternatives.indistinguishable`,
on the fits' open-loop held-out predictions, ``extra["open_loop_y"]``); before, such an answer
carried no list at all (the list was that of the segment reading, which had chosen nothing).
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from .alternatives import indistinguishable
from .fit import NEAR_FLOOR, choose, needs_explaining, unpriced_error

__all__ = ["choose_open_loop"]


def choose_open_loop(nominal_open_loop: dict, floor: dict, fits, evidence=None, measured=None):
    """The fit that predicts the held-out part open-loop to about the noise, or None, and the
    fits of other kinds the open-loop held-out part cannot tell apart from it.

    Parameters
    ----------
    nominal_open_loop : dict str -> float
        The nominal model's open-loop held-out NRMSE per output (inf where it diverges).
    floor : dict str -> float
        The measurement noise floor per output, as an NRMSE (:func:`diagnosis.fit.noise_floor`).
    fits : list of CandidateFit
        Their open-loop held-out NRMSE in ``extra["open_loop"]`` (:func:`diagnosis.fit.fit_candidate`).
    evidence : callable, optional
        As for :func:`diagnosis.fit.choose`.
    measured : dict str -> ndarray, optional
        The recorded held-out outputs; without them no alternative is resolved (all that tie are
        listed).

    Returns
    -------
    chosen : CandidateFit or None
        The fit itself (its held-out numbers stay the segment judge's), with
        ``extra["judge"] = "open-loop"`` and ``extra["open_loop_reading"]`` its open-loop NRMSE.
    alternatives : list of diagnosis.alternatives.Alternative
        Their held-out NRMSE the open-loop ones; empty when none is chosen.

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> from diagnosis.fit import CandidateFit
    >>> def fit(open_loop):
    ...     return CandidateFit(SimpleNamespace(kind="viscous_friction"), {}, {}, {"v": 0.03}, 1, True, "",
    ...                         extra={"open_loop": {"v": open_loop}})
    >>> near, drift_stopped = fit(0.03), fit(0.10)
    >>> choose_open_loop({"v": 1.5}, {"v": 0.02}, [near])[0] is near
    True
    >>> choose_open_loop({"v": 1.5}, {"v": 0.02}, [drift_stopped])
    (None, [])
    """
    pairs = []        # (fit, the same fit judged by its open-loop errors and prediction)
    for f in fits:
        reading = f.extra.get("open_loop") if f.success else None
        if reading and all(np.isfinite(reading.get(o, np.inf)) for o in nominal_open_loop):
            extra = {k: v for k, v in f.extra.items() if k not in ("holdout_y", "open_loop_y")}
            extra["holdout_y"] = f.extra.get("open_loop_y")          # not the segments' prediction
            pairs.append((f, replace(f, holdout_nrmse=dict(reading), extra=extra)))
    if not pairs:
        return None, []
    reference = {o: (v if np.isfinite(v) else 1.0) for o, v in nominal_open_loop.items()}
    judged = [p for _, p in pairs]
    best = choose(reference, judged, noise=floor, evidence=evidence)
    significant = needs_explaining(reference, floor)
    if best is None or not significant:
        return None, []
    if unpriced_error(best, significant) > NEAR_FLOOR ** 2 * sum(floor.get(o, 0.0) ** 2 for o in significant):
        return None, []
    original = next(f for f, p in pairs if p is best)
    original.extra["judge"] = "open-loop"
    original.extra["open_loop_reading"] = dict(best.holdout_nrmse)
    return original, indistinguishable(best, judged, reference, noise=floor, measured=measured)
