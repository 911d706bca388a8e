"""Sigma-point schemes of the unscented transform: Julier's (with kappa) and the scaled one.

Both place :math:`2n + 1` points symmetrically about the mean,

.. math::

    \\mathcal X_0 = \\hat x, \\quad
    \\mathcal X_i = \\hat x + \\sqrt{c}\\, L_{:,i}, \\quad
    \\mathcal X_{i+n} = \\hat x - \\sqrt{c}\\, L_{:,i}, \\quad i = 1..n,

where :math:`L` is the lower Cholesky factor of :math:`P` (:math:`L L^T = P`,
so :math:`\\sqrt c L_{:,i}` is the i-th row of the upper factor of :math:`cP`,
the paper's "i-th row of the square root matrix" and filterpy's ``U[i]``), and
differ in the spread :math:`c` and the weights :math:`W^m` (mean) and
:math:`W^c` (covariance):

* Julier [1]_, eqs. (13)-(15), (17) of [2]_: :math:`c = n + \\kappa`,
  :math:`W_0 = \\kappa/(n+\\kappa)`, :math:`W_i = 1/(2(n+\\kappa))`, :math:`W^c = W^m`;
* scaled (van der Merwe) [3]_: :math:`\\lambda = \\alpha^2 (n+\\kappa) - n`,
  :math:`c = n + \\lambda`, :math:`W^m_0 = \\lambda/(n+\\lambda)`,
  :math:`W^c_0 = W^m_0 + 1 - \\alpha^2 + \\beta`, :math:`W_i = 1/(2(n+\\lambda))`.

The paper [2]_ uses Julier's points with :math:`\\kappa = 0`, so
:math:`W_0 = 0`: the central point carries no weight.  The objects are
injected into :class:`~estimators.ukf.UnscentedKalmanFilter` (``Wm``, ``Wc``,
``num_sigmas()``, ``sigma_points(x, P)``, as filterpy's).

References
----------
.. [1] S. J. Julier, J. K. Uhlmann, "A new extension of the Kalman filter to
   nonlinear systems", Proc. SPIE 3068, 1997.
.. [2] T. Shin, T. Ibayashi, K. Kogiso, "Detailed dynamic model of antagonistic
   PAM system and its experimental validation", seed 000 (``docs/references.md``),
   Section III-A, eqs. (13)-(18).
.. [3] R. van der Merwe, "Sigma-point Kalman filters for probabilistic inference
   in dynamic state-space models", PhD thesis, OGI, 2004.
"""
from __future__ import annotations

import numpy as np

from estimators.errors import EstimatorError

__all__ = ["SigmaPoints", "JulierSigmaPoints", "MerweScaledSigmaPoints"]


class SigmaPoints:
    """Symmetric :math:`2n+1` sigma points with spread `scale` and weights `Wm`, `Wc`.

    Use :class:`JulierSigmaPoints` or :class:`MerweScaledSigmaPoints`; this base
    class holds what both share.

    Parameters
    ----------
    n : int
        State dimension (>= 1).
    scale : float
        Spread :math:`c > 0`: the points are :math:`\\hat x \\pm \\sqrt{c} L_{:,i}`.
    Wm, Wc : array_like, shape (2n + 1,)
        Weights of the mean and of the covariance.

    Attributes
    ----------
    n : int
    scale : float
    Wm, Wc : ndarray, shape (2n + 1,), read-only
    """

    def __init__(self, n: int, scale: float, Wm, Wc):
        if int(n) != n or n < 1:
            raise EstimatorError(f"sigma points: n must be an integer >= 1; found {n!r}", "n")
        if not (np.isfinite(scale) and scale > 0):
            raise EstimatorError(f"sigma points: the spread c must be finite and > 0; found {scale!r}",
                                 "scale")
        self.n = int(n)
        self.scale = float(scale)
        self.Wm = self._weights("Wm", Wm)
        self.Wc = self._weights("Wc", Wc)

    def _weights(self, name, w):
        w = np.array(w, dtype=float)
        if w.shape != (2 * self.n + 1,) or not np.isfinite(w).all():
            raise EstimatorError(f"sigma points: {name} must be {2 * self.n + 1} finite numbers; "
                                 f"found shape {w.shape}", name)
        w.flags.writeable = False
        return w

    def num_sigmas(self) -> int:
        """Number of sigma points, :math:`2n + 1`."""
        return 2 * self.n + 1

    def sigma_points(self, x, P) -> np.ndarray:
        """Sigma points of mean `x` and covariance `P`.

        Parameters
        ----------
        x : array_like, shape (n,)
            Mean.
        P : array_like, shape (n, n)
            Covariance, symmetric positive definite.

        Returns
        -------
        ndarray, shape (2n + 1, n)
            Row 0 is `x`, rows 1..n are :math:`x + \\sqrt c L_{:,i}`, rows
            n+1..2n are :math:`x - \\sqrt c L_{:,i}`.

        Raises
        ------
        EstimatorError
            Wrong shapes, or `P` is not positive definite (``name == "P"``).
        """
        x = np.asarray(x, dtype=float)
        P = np.asarray(P, dtype=float)
        n = self.n
        if x.shape != (n,) or P.shape != (n, n):
            raise EstimatorError(f"sigma points: expected x of shape ({n},) and P of shape ({n}, {n}); "
                                 f"found {x.shape} and {P.shape}", "x" if x.shape != (n,) else "P")
        try:
            L = np.linalg.cholesky(P)
        except np.linalg.LinAlgError:
            L = None
        if L is None or not np.isfinite(L).all():
            raise EstimatorError("sigma points: P is not positive definite (Cholesky failed)", "P")
        return spread(x, L, np.sqrt(self.scale))

    def _params(self) -> str:
        return ""

    def __repr__(self):
        return f"{type(self).__name__}(n={self.n}{self._params()})"


def spread(x: np.ndarray, L: np.ndarray, sqrt_c: float) -> np.ndarray:
    """Rows ``x``, ``x + sqrt_c L[:, i]``, ``x - sqrt_c L[:, i]`` (eqs. (13)-(15) of [2]_)."""
    A = sqrt_c * L.T            # row i: sqrt(c) times column i of L
    return np.vstack([x, x + A, x - A])


class JulierSigmaPoints(SigmaPoints):
    """Julier's sigma points with parameter :math:`\\kappa` (the paper's, eqs. (13)-(15), (17)).

    .. math::

        c = n + \\kappa, \\quad W_0 = \\frac{\\kappa}{n+\\kappa}, \\quad
        W_i = \\frac{1}{2(n+\\kappa)}, \\quad W^c = W^m.

    Parameters
    ----------
    n : int
        State dimension.
    kappa : float
        :math:`\\kappa > -n`; the paper's value is 0 (:math:`W_0 = 0`).
        Negative values give a negative :math:`W_0`, which can make the
        predicted covariance indefinite.

    Examples
    --------
    >>> pts = JulierSigmaPoints(4, kappa=0.0)
    >>> pts.Wm
    array([0.   , 0.125, 0.125, 0.125, 0.125, 0.125, 0.125, 0.125, 0.125])
    """

    def __init__(self, n: int, *, kappa: float = 0.0):
        kappa = float(kappa)
        if not (np.isfinite(kappa) and n + kappa > 0):
            raise EstimatorError(f"JulierSigmaPoints: need n + kappa > 0; found n={n!r}, kappa={kappa!r}",
                                 "kappa")
        self.kappa = kappa
        w = np.full(2 * int(n) + 1, 0.5 / (n + kappa))
        w[0] = kappa / (n + kappa)
        super().__init__(n, n + kappa, w, w)

    def _params(self):
        return f", kappa={self.kappa!r}"


class MerweScaledSigmaPoints(SigmaPoints):
    """Scaled sigma points of van der Merwe [3]_ (parameters alpha, beta, kappa).

    .. math::

        \\lambda = \\alpha^2 (n + \\kappa) - n, \\quad c = n + \\lambda, \\quad
        W^m_0 = \\frac{\\lambda}{n+\\lambda}, \\quad
        W^c_0 = W^m_0 + 1 - \\alpha^2 + \\beta, \\quad
        W_i = \\frac{1}{2(n+\\lambda)}.

    Parameters
    ----------
    n : int
        State dimension.
    alpha : float
        Spread, :math:`0 < \\alpha \\le 1` typically (``1e-3`` in [3]_).
    beta : float
        Prior knowledge of the distribution; 2 is optimal for a Gaussian.
    kappa : float
        Secondary scaling, usually 0 or :math:`3 - n`.

    Examples
    --------
    >>> pts = MerweScaledSigmaPoints(2, alpha=1.0, beta=2.0, kappa=1.0)
    >>> pts.scale, pts.Wm.round(4).tolist(), float(pts.Wc[0].round(4))
    (3.0, [0.3333, 0.1667, 0.1667, 0.1667, 0.1667], 2.3333)
    """

    def __init__(self, n: int, *, alpha: float = 1e-3, beta: float = 2.0, kappa: float = 0.0):
        alpha, beta, kappa = float(alpha), float(beta), float(kappa)
        lam = alpha ** 2 * (n + kappa) - n
        if not (np.isfinite([alpha, beta, kappa]).all() and alpha > 0 and n + lam > 0):
            raise EstimatorError(f"MerweScaledSigmaPoints: need alpha > 0 and alpha^2 (n + kappa) > 0; "
                                 f"found n={n!r}, alpha={alpha!r}, kappa={kappa!r}", "alpha")
        self.alpha, self.beta, self.kappa = alpha, beta, kappa
        wm = np.full(2 * int(n) + 1, 0.5 / (n + lam))
        wc = wm.copy()
        wm[0] = lam / (n + lam)
        wc[0] = lam / (n + lam) + (1.0 - alpha ** 2 + beta)
        super().__init__(n, n + lam, wm, wc)

    def _params(self):
        return f", alpha={self.alpha!r}, beta={self.beta!r}, kappa={self.kappa!r}"
