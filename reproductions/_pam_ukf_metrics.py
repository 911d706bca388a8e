"""Estimation-accuracy indices I, M and Q of seed 000 ([1]_, Section IV, before IV-A).

For an estimation error :math:`z(k) = \\xi(k) - \\hat\\xi(k)`, :math:`k = 0 \\dots N`,
of a sensor signal :math:`\\xi`:

.. math::

    \\mathbb{I}(z, N) = \\sqrt{\\frac{1}{N} \\sum_{k=0}^{N} z^2(k)}, \\qquad
    \\mathbb{M}(z) = \\max_k |z(k)|, \\qquad
    \\mathbb{Q}(z, \\xi, N) = \\frac{\\mathbb{M}(z)}{\\max_k \\xi(k) - \\min_k \\xi(k)}.

Reading: the sum runs over the N + 1 samples :math:`k = 0 \\dots N` and is divided
by N, as printed (the usual RMSE divides by N + 1; for the paper's
:math:`N = 130 \\times 10^3` the two differ by 4 ppm).  The check against the
paper's own numbers: :math:`\\mathbb{Q} = 3.50 / (19.1 + 20.3) = 0.0888`, printed
0.0887 (Section IV-A1).

References
----------
.. [1] T. Shin, T. Ibayashi, K. Kogiso, "Detailed dynamic model of antagonistic
   PAM system and its experimental validation: sensor-less angle and torque
   control with UKF", seed 000 (``docs/references.md``).
"""
from __future__ import annotations

import numpy as np
from .errors import ScenarioError

__all__ = ["rmse_index", "max_index", "ratio_index", "indices"]


def _error(z, name: str = "z") -> np.ndarray:
    z = np.asarray(z, dtype=float)
    if z.ndim != 1 or z.size < 2:
        raise ScenarioError(f"{name} must be a 1-D signal of at least 2 samples (k = 0..N, N >= 1); "
                         f"found shape {z.shape}")
    if not np.all(np.isfinite(z)):
        raise ScenarioError(f"{name} has {int(np.sum(~np.isfinite(z)))} non-finite value(s), the first at "
                         f"k = {int(np.argmax(~np.isfinite(z)))}")
    return z


def rmse_index(z) -> float:
    """:math:`\\mathbb{I}(z, N) = \\sqrt{\\sum_{k=0}^N z^2(k) / N}` (unit of `z`).

    Parameters
    ----------
    z : array_like, shape (N + 1,)
        Estimation error at k = 0..N, N >= 1.

    Examples
    --------
    >>> rmse_index([3.0, 4.0])     # sqrt((9 + 16) / 1)
    5.0
    """
    z = _error(z)
    return float(np.sqrt(np.sum(z * z) / (z.size - 1)))


def max_index(z) -> float:
    """:math:`\\mathbb{M}(z) = \\|z\\|_\\infty` (unit of `z`).

    Parameters
    ----------
    z : array_like, shape (N + 1,)
        Estimation error at k = 0..N, N >= 1.

    Examples
    --------
    >>> max_index([0.5, -2.0, 1.0])
    2.0
    """
    return float(np.max(np.abs(_error(z))))


def ratio_index(z, xi) -> float:
    """:math:`\\mathbb{Q}(z, \\xi, N) = \\mathbb{M}(z) / (\\max \\xi - \\min \\xi)` (1).

    Parameters
    ----------
    z : array_like, shape (N + 1,)
        Estimation error.
    xi : array_like, shape (N + 1,)
        The sensor signal (truth), same unit as `z`.

    Raises
    ------
    ValueError
        Shapes differ, or `xi` is constant (its range is zero).

    Examples
    --------
    >>> round(ratio_index([3.50, 0.0], [19.1, -20.3]), 4)    # Section IV-A1 of [1]_
    0.0888
    """
    z, xi = _error(z), _error(xi, "xi")
    if z.shape != xi.shape:
        raise ScenarioError(f"z and xi must have the same shape; found {z.shape} and {xi.shape}")
    span = float(np.max(xi) - np.min(xi))
    if span <= 0.0:
        raise ScenarioError("xi is constant: Q needs a signal with a non-zero range")
    return max_index(z) / span


def indices(truth, estimate) -> dict[str, float]:
    """``{"I", "M", "Q"}`` of the error ``truth - estimate`` against the range of `truth`.

    Parameters
    ----------
    truth, estimate : array_like, shape (N + 1,)
        Same unit (I and M are in it; Q is a ratio).

    Returns
    -------
    dict str -> float
    """
    truth, estimate = _error(truth, "truth"), _error(estimate, "estimate")
    if truth.shape != estimate.shape:
        raise ScenarioError(f"truth and estimate must have the same shape; found {truth.shape} and {estimate.shape}")
    z = truth - estimate
    return {"I": rmse_index(z), "M": max_index(z), "Q": ratio_index(z, truth)}
