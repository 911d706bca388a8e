"""Whether the held-out part resolves the difference between two fits' errors.

Two fits :math:`a` and :math:`b` predict :math:`\\hat y_a, \\hat y_b` on the held-out samples of
a recording :math:`y = y^\\ast + e`.  The difference of their squared errors,

.. math::

    D = \\sum_t (y_t - \\hat y_{b,t})^2 - (y_t - \\hat y_{a,t})^2
      = \\underbrace{\\sum_t w_t (2 y^\\ast_t - \\hat y_{a,t} - \\hat y_{b,t})}_{\\text{the fits' difference}}
        + 2 \\sum_t w_t e_t, \\qquad w = \\hat y_a - \\hat y_b,

is the fits' true difference plus a noise term of variance
:math:`4 \\sum_{t,s} w_t w_s C_e(t - s)`.  The recording is given (its inputs and the plant's
motion are what they are); what could have come out differently is the noise.  So the test is
conditional on the recording: :math:`z = D / \\sqrt{\\mathrm{Var}}` (the Diebold-Mariano
comparison of two forecasts, Diebold and Mariano, J. Bus. Econ. Stat. 13(3), 1995, with the
forecasts' difference known).  :math:`C_e` is estimated from the better fit's own residual up to
:func:`max_lag` lags with Bartlett weights (Newey and West, Econometrica 55(3), 1987), so what
that fit leaves unexplained enters the variance: coloured noise, or a slow mismatch both fits
share, widens it where the white-noise variance :math:`4 \\sigma^2 \\sum_t w_t^2` would claim a
resolution the recording does not hold.

:func:`diagnosis.fit.choose` lets two fits whose priced held-out errors are within 2 % of each
other tie (the tie goes to fewer parameters) unless the held-out part resolves the leader's
lower error, :math:`z \\ge` :data:`Z_RESOLVED`.  Each output enters over its spread, as the NRMSE
does.
"""
from __future__ import annotations

import numpy as np

__all__ = ["Z_RESOLVED", "held_out_prediction", "largest_difference", "max_lag", "resolution"]

#: z from which the held-out part resolves a difference (one-sided p of about 0.001)
Z_RESOLVED = 3.0
#: fewest scored held-out samples for a test
MIN_SAMPLES = 50


def held_out_prediction(predicted: dict) -> dict:
    """A fit's held-out outputs as kept for the test (float32: a 130 s, 1 kHz record's held-out
    part is 40 000 samples per output, for every fit of a round)."""
    return {o: np.asarray(v, dtype=np.float32) for o, v in predicted.items()}


def max_lag(n: int) -> int:
    """Lags of the residual's autocovariance used: a twentieth of the samples, at least one."""
    return max(1, n // 20)


def resolution(measured: dict | None, better: dict | None, worse: dict | None, outputs) -> float:
    """:math:`z` of `better`'s lower held-out error over `worse`'s (module docstring), summed
    over `outputs`, each over its spread.  NaN predictions (samples a segment judge does not
    score) are left out; NaN when fewer than :data:`MIN_SAMPLES` remain, nothing differs, or a
    prediction is missing (nothing to test).

    Examples
    --------
    White noise of 0.1 on 1000 samples; a fit off by 0.05 is resolved from the truth
    (:data:`Z_RESOLVED`), one off by 0.002 is not:

    >>> rng = np.random.default_rng(0)
    >>> t = np.linspace(0, 10, 1000); truth = np.sin(t); y = {"x": truth + 0.1 * rng.standard_normal(t.size)}
    >>> [bool(resolution(y, {"x": truth}, {"x": truth + off}, ["x"]) >= Z_RESOLVED) for off in (0.05, 0.002)]
    [True, False]
    """
    if measured is None or better is None or worse is None or not all(
            o in measured and o in better and o in worse for o in outputs):
        return float("nan")
    D = var = 0.0
    for o in outputs:
        y = np.asarray(measured[o], dtype=float)
        a, b = (np.asarray(p[o], dtype=float) for p in (better, worse))
        if not (y.shape == a.shape == b.shape):
            return float("nan")
        keep = np.isfinite(a) & np.isfinite(b) & np.isfinite(y)
        if keep.sum() < MIN_SAMPLES:
            return float("nan")
        spread = float(np.std(y[keep])) or 1.0
        y, a, b = y[keep] / spread, a[keep] / spread, b[keep] / spread
        w, r = a - b, y - a
        r = r - r.mean()
        D += float(np.sum((y - b) ** 2 - (y - a) ** 2))
        var += 4.0 * _weighted_long_run_variance(w, r, max_lag(y.size))
    if not var > 0.0:
        return float("nan")
    return D / np.sqrt(var)


def _weighted_long_run_variance(w, r, lags: int) -> float:
    """:math:`\\sum_{t,s} w_t w_s \\hat C(t - s)`, :math:`\\hat C` the autocovariance of `r` with
    Bartlett weights up to `lags` (never negative); both autocorrelations by FFT."""
    n = r.size
    size = 1 << int(np.ceil(np.log2(2 * n)))
    lags = min(lags, n - 1)
    c = np.fft.irfft(np.abs(np.fft.rfft(r, size)) ** 2, size)[:lags + 1] / n
    s = np.fft.irfft(np.abs(np.fft.rfft(w, size)) ** 2, size)[:lags + 1]
    weights = np.concatenate([[1.0], 2.0 * (1.0 - np.arange(1, lags + 1) / (lags + 1.0))])
    return max(float(np.sum(weights * c * s)), 0.0)


def largest_difference(measured: dict | None, a: dict | None, b: dict | None, outputs, floor: dict) -> float:
    """Largest :math:`|\\hat y_a - \\hat y_b|` of two held-out predictions over `outputs`, in
    noise standard deviations (`floor`, each output's noise as an NRMSE, times the measured
    output's spread); NaN when a prediction or a measured output is missing.  A recording that
    excites the two fits' difference beyond the noise would tell them apart.

    Examples
    --------
    >>> y = {"x": np.linspace(0.0, 1.0, 11)}
    >>> round(largest_difference(y, {"x": y["x"]}, {"x": y["x"] + 0.01}, ["x"], {"x": 0.1}), 3)
    0.316
    """
    if measured is None or a is None or b is None:
        return float("nan")
    largest = float("nan")
    for o in outputs:
        if o not in a or o not in b or o not in measured:
            return float("nan")
        sigma = floor.get(o, 0.0) * float(np.nanstd(np.asarray(measured[o], dtype=float)))
        gap = np.abs(np.asarray(a[o], dtype=float) - np.asarray(b[o], dtype=float))
        if sigma > 0 and np.isfinite(gap).any():
            largest = float(np.nanmax([largest, np.nanmax(gap) / sigma]))
    return largest
