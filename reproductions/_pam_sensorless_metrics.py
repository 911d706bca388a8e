"""The steady-state tracking performance of seed 000, Section IV.C, and Fig. 14-like plots.

[1]_ reads the worst steady-state tracking error off Fig. 14 and divides it by
the range of the references: "the worst-case steady-state error is
2.1/40 = 0.0525 (5.25 %) ... steady-state tracking control performance of
94.75 %" (angle, references within +-20 deg) and "0.2/4.0 = 0.05 (5.0 %) ...
95.0 %" (torque, +-2 N m).  With the actual tracking error
:math:`\\zeta = \\bar\\cdot - \\cdot` (reference minus the TRUE signal, not the
estimate):

.. math::

    \\mathrm{performance} = 100\\,\\Big(1 - \\frac{\\max_{k \\in \\mathcal S} |\\zeta(k)|}
        {\\max_k \\bar\\cdot(k) - \\min_k \\bar\\cdot(k)}\\Big)\\ \\%

where :math:`\\mathcal S` are the steady-state samples.  The paper does not
define them; our reading: the samples at least ``settle`` seconds after the
last reference change (or after the start), i.e. the end of each
constant-reference segment.

References
----------
.. [1] T. Shin, T. Ibayashi, K. Kogiso, "Detailed dynamic model of antagonistic
   PAM system and its experimental validation: sensor-less angle and torque
   control with UKF", seed 000 (``docs/references.md``).
"""
from __future__ import annotations

import numpy as np

from .errors import CosimError

__all__ = ["steady_state_mask", "steady_state_performance", "plot_loop"]


def steady_state_mask(t, reference, settle: float) -> np.ndarray:
    """Samples at least `settle` s after the start or the last change of `reference`.

    Parameters
    ----------
    t : array_like, shape (N,), s
        Increasing sample times.
    reference : array_like, shape (N,)
        Step-like reference (any unit).
    settle : float, s
        Time allowed for the transient, >= 0.

    Returns
    -------
    ndarray of bool, shape (N,)
    """
    t, r = np.asarray(t, float), np.asarray(reference, float)
    if t.ndim != 1 or r.shape != t.shape or t.size == 0:
        raise CosimError(f"steady_state_mask: t and reference must be 1-D of equal length; "
                         f"found shapes {t.shape} and {r.shape}")
    if not (np.isfinite(settle) and settle >= 0):
        raise CosimError(f"steady_state_mask: settle must be a finite time >= 0 s; found {settle!r}")
    starts = np.concatenate([[0], np.flatnonzero(np.diff(r) != 0) + 1])
    segment_start = t[starts][np.searchsorted(starts, np.arange(t.size), side="right") - 1]
    return t - segment_start >= settle - 1e-12 * max(1.0, abs(settle))


def steady_state_performance(t, reference, actual, *, settle: float) -> dict:
    """The paper's steady-state tracking performance (module docstring).

    Parameters
    ----------
    t : array_like, shape (N,), s
    reference : array_like, shape (N,)
        Reference :math:`\\bar\\cdot` (deg or N m).
    actual : array_like, shape (N,)
        True (sensor) signal, same unit.
    settle : float, s
        See :func:`steady_state_mask`.

    Returns
    -------
    dict
        ``steady_state_performance_pct`` (%), ``worst_steady_state_error`` and
        ``reference_span`` (unit of the reference), ``steady_state_samples``,
        ``worst_error_per_step``: (reference value, worst steady-state signed
        error :math:`\\zeta`) per constant-reference segment that has steady samples.

    Raises
    ------
    CosimError
        Shapes differ, the reference is constant, or no sample is in steady state.

    Examples
    --------
    The paper's angle case: a worst steady-state error of 2.1 deg over references spanning 40 deg:

    >>> t = [0.0, 1.0, 2.0, 3.0]
    >>> p = steady_state_performance(t, [20, 20, -20, -20], [25, 18.5, -10, -17.9], settle=1.0)
    >>> round(p["steady_state_performance_pct"], 6), round(p["worst_steady_state_error"], 6)
    (94.75, 2.1)
    """
    r, y = np.asarray(reference, float), np.asarray(actual, float)
    if y.shape != r.shape:
        raise CosimError(f"steady_state_performance: actual has shape {y.shape}, the reference {r.shape}")
    mask = steady_state_mask(t, r, settle)
    span = float(r.max() - r.min())
    if span <= 0:
        raise CosimError("steady_state_performance: the reference is constant (its range is 0)")
    if not mask.any():
        raise CosimError(f"steady_state_performance: no sample lies {settle} s after a reference change")
    zeta = r - y
    worst = float(np.abs(zeta)[mask].max())
    starts = np.concatenate([[0], np.flatnonzero(np.diff(r) != 0) + 1, [r.size]])
    per_step = []
    for a, b in zip(starts[:-1], starts[1:]):
        z = zeta[a:b][mask[a:b]]
        if z.size:
            per_step.append([float(r[a]), float(z[np.argmax(np.abs(z))])])
    return {"steady_state_performance_pct": 100.0 * (1.0 - worst / span),
            "worst_steady_state_error": worst, "reference_span": span,
            "steady_state_samples": int(mask.sum()), "worst_error_per_step": per_step}


def plot_loop(t, reference, estimate, actual, u1, u2, *, quantity: str, unit: str, settle: float):
    """Fig. 14 of [1]_ for one loop, plus the valve commands.

    Top: reference (black dashed), UKF estimate (red), true value (green);
    middle: tracking error :math:`\\zeta`, steady-state samples marked;
    bottom: valve commands (V).

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    t = np.asarray(t)
    zeta = np.asarray(reference) - np.asarray(actual)
    mask = steady_state_mask(t, reference, settle)
    fig, axes = plt.subplots(3, 1, figsize=(9, 7.5), sharex=True,
                             gridspec_kw={"height_ratios": [2, 1, 1]})
    axes[0].plot(t, reference, "k--", lw=1.2, label="reference")
    axes[0].plot(t, estimate, "r", lw=1.0, label="UKF estimate")
    axes[0].plot(t, actual, "g", lw=1.0, label="true (sensor)")
    axes[0].set_ylabel(f"{quantity} [{unit}]")
    axes[0].legend(loc="best", fontsize=8)
    axes[1].plot(t, zeta, "b", lw=0.8)
    axes[1].plot(t[mask], zeta[mask], ".", color="orange", ms=1.5, label="steady state")
    axes[1].set_ylabel(f"tracking error [{unit}]")
    axes[1].legend(loc="best", fontsize=8)
    axes[2].plot(t, u1, lw=0.8, label="u1 (PDCV1)")
    axes[2].plot(t, u2, lw=0.8, label="u2 (PDCV2)")
    axes[2].set_ylabel("valve command [V]")
    axes[2].set_xlabel("time [s]")
    axes[2].legend(loc="best", fontsize=8)
    for ax in axes:
        ax.grid(alpha=0.3)
    fig.suptitle(f"UKF-based sensor-less {quantity} PI control (seed 000, Fig. 13-14)")
    fig.tight_layout()
    return fig
