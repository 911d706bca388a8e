"""How finely a junction correction must resolve time: from the residual's excited band.

The junction correction of :mod:`diagnosis.graph_location` is piecewise linear
on at most :data:`~diagnosis.graph_location._MAX_KNOTS` knots.  Spread over the
whole record, their spacing follows the record's length, not the model's
dynamics: 500 knots over 30 s are 60 ms apart and cannot follow the extra force
of a spring oscillating at 70 Hz.  What the correction must follow is what it
has to explain: the residual.  Its excited band is read from its power
spectrum (Welch) with the white measurement noise's level subtracted,

.. math::

    P_{ex}(f) = \\max\\bigl(P_r(f) - 2\\sigma^2 \\Delta t, 0\\bigr),

where the noise level is the larger of the estimated :math:`\\sigma` 's and the median
power in the top fifth of the band (white noise the estimate missed), raised by three
standard errors of the Welch average so that the noise's own scatter is no excess;
:math:`f_{95}` is the frequency below which 95 % of :math:`\\sum P_{ex}` lies (the
largest over the outputs).  A hat basis of spacing :math:`h` follows
a sinusoid of period :math:`T` to within a few per cent when :math:`h \\le T/4`,
so the knots are :math:`h = 1 / (4 f_{95})` apart.  When the record is longer
than the knots then cover, the location runs on the window of that length where
the residual changes most (:func:`busiest_window`), restarted from the nominal
simulation's state there: the cost stays that of :data:`_MAX_KNOTS` knots.
"""
from __future__ import annotations

import numpy as np

__all__ = ["excited_band", "knot_spacing", "busiest_window"]

#: share of the residual's excess power below the band's upper edge
BAND_SHARE = 0.95
#: knot spacing as a fraction of the shortest period in the band
PER_PERIOD = 0.25


def excited_band(residual: dict, noise: dict, dt: float) -> float:
    """Upper edge of the residual's excited band, Hz (0 when no output has power above its noise).

    Parameters
    ----------
    residual : dict str -> ndarray
        Residual (measured - simulated) per output, on a uniform grid of step `dt`.
    noise : dict str -> float
        Measurement noise standard deviation per output (output units).
    dt : float
        Sample interval, s.
    """
    from scipy.signal import welch

    edge = 0.0
    for o, r in residual.items():
        r = np.asarray(r, dtype=float)
        if r.size < 16 or not np.isfinite(r).all():
            continue
        nperseg = min(r.size, 4096)
        f, p = welch(r - np.mean(r), fs=1.0 / dt, nperseg=nperseg, detrend="linear")
        level = max(2.0 * noise.get(o, 0.0) ** 2 * dt, float(np.median(p[f >= 0.8 * f[-1]])))
        segments = max(1.0, 2.0 * r.size / nperseg - 1.0)      # Welch averages, half overlapping
        excess = np.clip(p - (1.0 + 3.0 / np.sqrt(segments)) * level, 0.0, None)
        total = float(np.sum(excess))
        if total <= 0.0 or total * (f[1] - f[0]) < 0.1 * noise.get(o, 0.0) ** 2:
            continue            # the residual stays at the noise level: nothing to resolve here
        edge = max(edge, float(f[np.searchsorted(np.cumsum(excess), BAND_SHARE * total)]))
    return edge


def knot_spacing(residual: dict, noise: dict, dt: float) -> float:
    """Largest knot spacing that follows the residual's band, s (inf when nothing needs it)."""
    band = excited_band(residual, noise, dt)
    return PER_PERIOD / band if band > 0 else float("inf")


def busiest_window(residual: dict, weight: dict, length: int) -> int:
    """First index of the `length`-sample window where the residual changes most.

    The score of a window starting at ``a`` is the weighted sum over outputs of
    :math:`\\sum_{k \\in [a, a+L)} (r_k - r_a)^2`: what the window's own dynamics
    must explain (an offset inherited from before the window is no part of it).
    Windows start on a grid of a quarter window.
    """
    n = len(next(iter(residual.values())))
    if length >= n:
        return 0
    starts = np.unique(np.r_[np.arange(0, n - length, max(1, length // 4)), n - length])
    best, best_score = 0, -1.0
    for a in starts:
        score = sum(weight[o] * float(np.sum((np.asarray(r[a:a + length]) - r[a]) ** 2))
                    for o, r in residual.items())
        if score > best_score:
            best, best_score = int(a), score
    return best
