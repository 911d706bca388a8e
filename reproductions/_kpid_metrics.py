"""Performance indicators of Tables 1-2 of seed 002 [1]_, with the definitions used.

The paper names the indicators but does not define them; we use the
standard textbook definitions, stated here and in ``docs/reproduction_kpid.md``:

- **tracking precision** (Table 1, periodic reference), %:
  :math:`100 \\cdot \\mathrm{mean}_k |y_{d,k} - y_k| / (\\max y_d - \\min y_d)`
  over the whole run (mean absolute error relative to the reference's range;
  lower is better, as in the paper);
- **rise time** (Table 2, step), s: 10 % to 90 % of the step, first crossings;
- **overshoot**, %: :math:`100 \\max(0, \\max_k y_k - y_d) / (y_d - y_0)`;
- **settling time**, s: start of the final stretch within ±2 % of the step
  around the reference (``None`` if the run ends outside the band);
- **steady-state error**, mm: mean :math:`|y_d - y|` over the last quarter
  of the run (the chatter counts; the signed mean is reported as the bias).

References
----------
.. [1] Yang H. et al., Control Theory & Applications (2017);
   seed 002 (``docs/references.md``).
"""
from __future__ import annotations

import numpy as np
from .errors import ScenarioError

__all__ = ["tracking_precision_pct", "step_metrics", "SETTLING_BAND", "STEADY_FRACTION"]

#: Settling band, fraction of the step size.
SETTLING_BAND = 0.02
#: Fraction of the run (at its end) over which the steady-state error is averaged.
STEADY_FRACTION = 0.25


def _arrays(t, y, name="y"):
    t, y = np.asarray(t, dtype=float), np.asarray(y, dtype=float)
    if t.ndim != 1 or t.shape != y.shape or t.size < 2:
        raise ScenarioError(f"{name}: expected 1-D t and {name} of the same length >= 2; "
                         f"found shapes {t.shape} and {y.shape}")
    return t, y


def tracking_precision_pct(reference, y) -> float:
    """Mean absolute tracking error relative to the reference range, %.

    Parameters
    ----------
    reference, y : array_like, shape (n,)
        :math:`y_d` and the output, same unit.
    """
    yd, y = np.asarray(reference, dtype=float), np.asarray(y, dtype=float)
    span = float(np.max(yd) - np.min(yd))
    if yd.shape != y.shape or span <= 0.0:
        raise ScenarioError("tracking_precision_pct needs a non-constant reference and an output "
                         f"of the same shape; found shapes {yd.shape}, {y.shape}, range {span}")
    return float(100.0 * np.mean(np.abs(yd - y)) / span)


def _first_crossing(t, y, level, rising):
    hit = np.nonzero(y >= level if rising else y <= level)[0]
    return float(t[hit[0]]) if hit.size else None


def step_metrics(t, y, target: float, *, y0: float = 0.0) -> dict:
    """Rise time, overshoot, settling time and steady-state error of a step response.

    Parameters
    ----------
    t : array_like, shape (n,), s
        Sample times; the step is applied at ``t[0]``.
    y : array_like, shape (n,)
        Response (mm).
    target : float
        Reference after the step (mm).
    y0 : float, optional
        Output before the step (mm).

    Returns
    -------
    dict
        ``rise_time_s``, ``overshoot_pct``, ``settling_time_s`` (``None`` where not
        reached), ``steady_state_error_mm`` (mean absolute error over the last
        quarter), ``steady_state_bias_mm`` (mean signed error ``target - y`` there).
    """
    t, y = _arrays(t, y)
    step = float(target) - float(y0)
    if step == 0.0:
        raise ScenarioError("step_metrics: target equals y0 (no step)")
    rising = step > 0
    t10 = _first_crossing(t, y, y0 + 0.1 * step, rising)
    t90 = _first_crossing(t, y, y0 + 0.9 * step, rising)
    rise = None if t10 is None or t90 is None else t90 - t10
    peak = np.max(y) if rising else np.min(y)
    overshoot = max(0.0, 100.0 * (peak - target) / step)
    outside = np.nonzero(np.abs(y - target) > SETTLING_BAND * abs(step))[0]
    if outside.size == 0:
        settling = 0.0
    elif outside[-1] == y.size - 1:
        settling = None
    else:
        settling = float(t[outside[-1] + 1] - t[0])
    tail = slice(int(np.floor((1.0 - STEADY_FRACTION) * y.size)), None)
    err = float(target) - y[tail]
    return {"rise_time_s": rise, "overshoot_pct": float(overshoot), "settling_time_s": settling,
            "steady_state_error_mm": float(np.mean(np.abs(err))),
            "steady_state_bias_mm": float(np.mean(err))}
