"""The numpy reference engine of the UKF: the paper's equations, one numpy call per line.

:class:`NumpyEngine` is the readable reference (and the fallback) of
:class:`estimators.ukf.UnscentedKalmanFilter`; the compiled engine
(:class:`estimators.ukf_c.CEngine`) does the same arithmetic in one C call.
Both keep the filter state and expose the same attributes (``x``, ``P``,
``x_prior``, ``P_prior``, ``K``, ``S``, ``y_pred``, ``innovation``, ``d``,
``t``, ``k``, ``sigmas_f``).

Equations (eqs. (13)-(24) of [1]_, weights :math:`W^m`, :math:`W^c`, spread :math:`c`):

.. math::

    \\mathcal X = [\\hat x,\\ \\hat x \\pm \\sqrt c L_{:,i}], \\quad L L^T = P \\\\
    \\mathcal X^-_i = f(\\mathcal X_i, u), \\quad
    \\hat x^- = \\sum W^m_i \\mathcal X^-_i, \\quad
    P^- = \\sum W^c_i (\\mathcal X^-_i - \\hat x^-)(\\cdot)^T + Q \\\\
    \\mathcal Y_i = h(\\mathcal X'_i), \\quad
    \\hat y = \\sum W^m_i \\mathcal Y_i, \\quad
    S = \\sum W^c_i (\\mathcal Y_i - \\hat y)(\\cdot)^T + R, \\quad
    P_{xy} = \\sum W^c_i (\\mathcal X'_i - \\hat x^-)(\\mathcal Y_i - \\hat y)^T \\\\
    K = P_{xy} S^{-1}, \\quad \\hat x = \\hat x^- + K (y - \\hat y), \\quad
    P = P^- - K S K^T

with :math:`\\mathcal X' = [\\hat x^-,\\ \\hat x^- \\pm \\sqrt c L^-_{:,i}]`,
:math:`L^- L^{-T} = P^-` when ``redraw`` (the paper: "the sigma points are
recalculated using :math:`\\hat x^-(k)` and :math:`P^-(k)`"; filterpy 2.0 does
the same), else :math:`\\mathcal X' = \\mathcal X^-` (filterpy 1.4).  The paper
prints :math:`K = P_{xy}/(P_{yy} + R)` with :math:`P_{yy}` of eq. (21), which
already contains :math:`R`; we add :math:`R` once, as the UKF of [2]_.

References
----------
.. [1] T. Shin, T. Ibayashi, K. Kogiso, "Detailed dynamic model of antagonistic
   PAM system and its experimental validation", seed 000 (``docs/references.md``),
   Section III-A.
.. [2] S. J. Julier, J. K. Uhlmann, "A new extension of the Kalman filter to
   nonlinear systems", Proc. SPIE 3068, 1997.
"""
from __future__ import annotations

import numpy as np
from scipy.linalg import cho_solve

from estimators.errors import EstimatorError

from .sigma_points import spread

__all__ = ["NumpyEngine"]


class NumpyEngine:
    """Numpy UKF engine (see the module docstring).

    Parameters
    ----------
    propagate : callable (X, u, t, d) -> (X_new, d_new)
        Sigma points (N, n) after one sample; held values after it.
    measure : callable (X, u, t, d) -> Y
        Measurements (N, m) of sigma points (N, n).
    points : SigmaPoints
    redraw : bool
    x0, P0, Q, R : ndarray
        Validated initial state and covariances.
    t0, dt : float, s
    d0 : ndarray, shape (n_held,)
    u0 : ndarray or None
        Input used by :meth:`predict` until one is given (then the last one).
    """

    kind = "numpy"

    def __init__(self, propagate, measure, points, redraw, x0, P0, Q, R, t0, dt, d0, u0=None):
        self._propagate, self._measure = propagate, measure
        self.Wm, self.Wc, self._sqrt_c = points.Wm, points.Wc, np.sqrt(points.scale)
        self.redraw = bool(redraw)
        self.x, self.P, self.Q, self.R = x0.copy(), P0.copy(), Q, R
        self.x_prior, self.P_prior = x0.copy(), P0.copy()
        n, m = x0.size, R.shape[0]
        self.K, self.S = np.zeros((n, m)), R.copy()
        self.y_pred, self.innovation = np.zeros(m), np.zeros(m)
        self.sigmas_f = np.tile(x0, (2 * n + 1, 1))
        self.t, self.dt, self.d = float(t0), float(dt), np.array(d0, dtype=float)
        self.k = 0
        self.u = u0

    def set_state(self, x=None, P=None):
        if x is not None:
            self.x = np.array(x, dtype=float)
        if P is not None:
            self.P = np.array(P, dtype=float)

    def _fail(self, what, name, message):
        raise EstimatorError(f"UKF {what} at step {self.k} (t = {self.t:.9g} s): {message}", name,
                             step=self.k, time=self.t)

    def _chol(self, M, name, what, label):
        try:
            L = np.linalg.cholesky(M)
        except np.linalg.LinAlgError:
            L = None
        if L is None or not np.isfinite(L).all():
            self._fail(what, name, f"{label} is not positive definite (Cholesky failed)")
        return L

    def _checked(self, A, shape, name, what):
        A = np.asarray(A, dtype=float)
        if A.shape != shape:
            self._fail(what, name, f"{name} returned shape {A.shape}; expected {shape}")
        if not np.isfinite(A).all():
            rows = np.flatnonzero(~np.isfinite(A).all(axis=1))
            self._fail(what, name, f"{name} returned non-finite values for sigma point(s) "
                                   f"{', '.join(map(str, rows[:10]))}")
        return A

    def predict(self, u):
        if u is None:
            u = self.u
        # eqs. (13)-(15): sigma points of the posterior (L L^T = P)
        L = self._chol(self.P, "P", "predict", "the covariance P")
        X = spread(self.x, L, self._sqrt_c)
        # eq. (16): every point through the process model, in one batch
        Xp, d = self._propagate(X, u, self.t, self.d)
        Xp = self._checked(Xp, X.shape, "fx", "predict")
        # eqs. (17)-(18): prior mean and covariance
        x = self.Wm @ Xp
        dX = Xp - x
        P = dX.T @ (self.Wc[:, None] * dX) + self.Q
        P = 0.5 * (P + P.T)
        self.sigmas_f, self.d, self.u = Xp, np.asarray(d, dtype=float), u
        self.x_prior, self.P_prior = x, P
        self.x, self.P = x.copy(), P.copy()
        self.t += self.dt
        self.k += 1

    def update(self, z, u):
        if u is None:
            u = self.u
        x_prior, P_prior = self.x_prior, self.P_prior
        if self.redraw:
            # the paper: sigma points recomputed from x^-, P^- before eq. (19)
            L = self._chol(P_prior, "P_prior", "update", "the prior covariance P⁻")
            X = spread(x_prior, L, self._sqrt_c)
        else:
            X = self.sigmas_f
        m = self.R.shape[0]
        # eq. (19): measurements of every point
        Y = self._checked(self._measure(X, u, self.t, self.d), (X.shape[0], m), "hx", "update")
        # eqs. (20)-(22)
        y_pred = self.Wm @ Y
        dY = Y - y_pred
        S = dY.T @ (self.Wc[:, None] * dY) + self.R
        S = 0.5 * (S + S.T)
        Pxy = (X - x_prior).T @ (self.Wc[:, None] * dY)
        # K = P_xy S^-1 by Cholesky solves (S = P_yy including R, see the module docstring)
        Ls = self._chol(S, "S", "update", "the innovation covariance S")
        K = cho_solve((Ls, True), Pxy.T).T
        # eqs. (23)-(24)
        self.innovation = z - y_pred
        self.x = x_prior + K @ self.innovation
        P = P_prior - K @ S @ K.T
        self.P = 0.5 * (P + P.T)
        self.K, self.S, self.y_pred = K, S, y_pred
