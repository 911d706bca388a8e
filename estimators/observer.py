"""Steady-state Kalman gains from the Riccati equations, and the fixed-gain
observers built on them.

- :func:`discrete_kalman_gain`: discrete algebraic Riccati equation (DARE),
  the limit of :class:`~estimators.kalman.KalmanFilter` for ``k -> inf``;
  :class:`SteadyStateKalmanFilter` runs it.
- :func:`continuous_kalman_gain`: continuous algebraic Riccati equation
  (CARE), the Kalman-Bucy gain of eq. (9) of [1]_;
  :class:`ContinuousObserver` runs that observer (eq. (8) of [1]_) at a fixed
  sampling period, discretised exactly with zero-order-hold inputs.

Both designs first check detectability of ``(A, C)`` and report an
unobservable, unstable mode by eigenvalue and state combination
(:class:`~bondgraph.errors.UnobservableModeError`); python-control's
``dlqe``/``lqe`` give the same gains (tested to 1e-9).

References
----------
.. [1] Exoskeleton bond graph / Kalman observer paper,
   seed 004 (``docs/references.md``), Section 3, eqs. (8)-(9).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
import scipy.linalg

from estimators.errors import EstimatorError

from ._linalg import as_matrix, as_vector, check_covariance, riccati_call, zoh
from .kalman import KalmanResult
from .modes import check_detectable

__all__ = ["ObserverGain", "discrete_kalman_gain", "continuous_kalman_gain",
           "SteadyStateKalmanFilter", "ContinuousObserver"]


@dataclass(frozen=True)
class ObserverGain:
    """A steady-state Kalman design.

    Attributes
    ----------
    discrete : bool
    L : ndarray, shape (n, p)
        Observer (predictor) gain: discrete ``x^-_{k+1} = F x^-_k + B u_k + L (z_k - H x^-_k - D u_k)``;
        continuous ``x_hat' = A x_hat + B u + L (y - C x_hat - D u)``.
    P : ndarray, shape (n, n)
        Riccati solution: discrete, the steady prior covariance :math:`P^-`;
        continuous, the error covariance.
    poles : ndarray, shape (n,)
        Eigenvalues of the estimation-error dynamics ``F - L H`` (or ``A - L C``).
    K : ndarray, shape (n, p) or None
        Discrete only: the filter (update) gain :math:`P^- H^T S^{-1}`, so ``L = F K``.
    P_post : ndarray, shape (n, n) or None
        Discrete only: the steady posterior covariance.
    """

    discrete: bool
    L: np.ndarray
    P: np.ndarray
    poles: np.ndarray
    K: np.ndarray | None = None
    P_post: np.ndarray | None = None


def _noise(A, C, Q, R, G, owner):
    A = as_matrix(A, "A", (None, None), owner=owner)
    n = A.shape[0]
    if A.shape != (n, n):
        raise EstimatorError(f"{owner}: A: expected a square matrix but found shape {A.shape}", name="A")
    C = as_matrix(C, "C", (None, n), owner=owner)
    G = np.eye(n) if G is None else as_matrix(G, "G", (n, None), owner=owner)
    Q = check_covariance(Q, "Q", G.shape[1], definite=False, owner=owner)
    R = check_covariance(R, "R", C.shape[0], definite=True, owner=owner)
    return A, C, G @ Q @ G.T, R


def discrete_kalman_gain(F, H, Q, R, *, G=None, state_names: Sequence[str] | None = None) -> ObserverGain:
    """Steady-state gain of the discrete Kalman filter (DARE).

    .. math::

        P = F P F^T - F P H^T (H P H^T + R)^{-1} H P F^T + G Q G^T, \\qquad
        K = P H^T (H P H^T + R)^{-1}, \\qquad L = F K

    Parameters
    ----------
    F : array_like, shape (n, n)
    H : array_like, shape (p, n)
    Q : array_like, shape (q, q)
        Process-noise covariance (PSD), entering through `G`.
    R : array_like, shape (p, p)
        Measurement-noise covariance (PD).
    G : array_like, shape (n, q), optional
        Noise input matrix (identity by default, then ``q = n``).
    state_names : sequence of str, optional
        For the error message of an undetectable pair.

    Returns
    -------
    ObserverGain
        With ``discrete=True``; ``L`` and ``P`` equal python-control's ``dlqe(F, G, H, Q, R)``.

    Raises
    ------
    UnobservableModeError
        ``(F, H)`` has an unobservable mode with ``|z| >= 1``.
    EstimatorError
        Bad matrices, or no stabilising DARE solution.
    """
    own = "discrete_kalman_gain"
    F, H, Qn, R = _noise(F, H, Q, R, G, own)
    check_detectable(F, H, discrete=True, state_names=state_names, owner=own)
    P = riccati_call(scipy.linalg.solve_discrete_are, F.T, H.T, Qn, R, what=own)
    S = H @ P @ H.T + R
    K = scipy.linalg.solve(S, H @ P, assume_a="pos").T
    IKH = np.eye(F.shape[0]) - K @ H
    P_post = IKH @ P @ IKH.T + K @ R @ K.T
    L = F @ K
    poles = np.linalg.eigvals(F - L @ H)
    if poles.size and np.max(np.abs(poles)) >= 1.0:
        raise EstimatorError(f"{own}: the steady-state filter is not stable (max |pole| = "
                             f"{np.max(np.abs(poles)):.6g}); check that (F, G Q^1/2) has no mode on |z| = 1")
    return ObserverGain(True, L, P, poles, K, 0.5 * (P_post + P_post.T))


def continuous_kalman_gain(A, C, Q, R, *, G=None, state_names: Sequence[str] | None = None) -> ObserverGain:
    """Steady-state Kalman-Bucy gain (CARE), eq. (9) of [1]_.

    .. math::

        A P + P A^T - P C^T R^{-1} C P + G Q G^T = 0, \\qquad L = P C^T R^{-1}

    Parameters
    ----------
    A : array_like, shape (n, n)
        rad/s (1/s) entries.
    C : array_like, shape (p, n)
    Q : array_like, shape (q, q)
        Process-noise intensity (PSD; units of x_i x_j per s), entering through `G`.
    R : array_like, shape (p, p)
        Measurement-noise intensity (PD; units of y_i y_j s).
    G : array_like, shape (n, q), optional
        Noise input matrix (identity by default).
    state_names : sequence of str, optional
        For the error message of an undetectable pair.

    Returns
    -------
    ObserverGain
        With ``discrete=False``; ``L`` and ``P`` equal python-control's ``lqe(A, G, C, Q, R)``.

    Raises
    ------
    UnobservableModeError
        ``(A, C)`` has an unobservable mode with ``Re >= 0``, such as the
        rigid-body mode of the exoskeleton model with absolute angles.
    EstimatorError
        Bad matrices, or no stabilising CARE solution.
    """
    own = "continuous_kalman_gain"
    A, C, Qn, R = _noise(A, C, Q, R, G, own)
    check_detectable(A, C, discrete=False, state_names=state_names, owner=own)
    P = riccati_call(scipy.linalg.solve_continuous_are, A.T, C.T, Qn, R, what=own)
    L = scipy.linalg.solve(R, C @ P, assume_a="pos").T
    poles = np.linalg.eigvals(A - L @ C)
    if poles.size and np.max(poles.real) >= 0.0:
        raise EstimatorError(f"{own}: the observer is not stable (max Re pole = {np.max(poles.real):.6g}); "
                             f"check that (A, G Q^1/2) has no mode on the imaginary axis")
    return ObserverGain(False, L, P, poles)


def _batch(zs, us, p, m, owner):
    zs = np.array(zs, dtype=float)
    zs = zs[:, None] if zs.ndim == 1 and p == 1 else zs
    if zs.ndim != 2 or zs.shape[1] != p:
        raise EstimatorError(f"{owner}: expected measurements of shape (N, {p}) but found {zs.shape}", name="zs")
    us = np.zeros((zs.shape[0], m)) if us is None else np.array(us, dtype=float)
    us = us[:, None] if us.ndim == 1 and m == 1 else us
    if us.shape != (zs.shape[0], m):
        raise EstimatorError(f"{owner}: expected inputs of shape ({zs.shape[0]}, {m}) but found {us.shape}",
                             name="us")
    return zs, us


class SteadyStateKalmanFilter:
    """Discrete Kalman filter with the constant gain of :func:`discrete_kalman_gain`.

    Same recursions and batch convention as
    :class:`~estimators.kalman.KalmanFilter` with ``K`` fixed and no
    covariance propagation.

    Parameters
    ----------
    F, H, Q, R, G : array_like
        As :func:`discrete_kalman_gain`.
    B : array_like, shape (n, m), optional
    D : array_like, shape (p, m), optional
    x0 : array_like, shape (n,), optional
        Prior mean at sample 0 (zeros by default).
    state_names : sequence of str, optional

    Attributes
    ----------
    gain : ObserverGain
    x : ndarray, shape (n,)
    """

    def __init__(self, F, H, Q, R, *, G=None, B=None, D=None, x0=None, state_names=None):
        own = "SteadyStateKalmanFilter"
        self.gain = discrete_kalman_gain(F, H, Q, R, G=G, state_names=state_names)
        self.F = as_matrix(F, "F", (None, None), owner=own)
        self.H = as_matrix(H, "H", (None, self.F.shape[0]), owner=own)
        n, p = self.H.shape[1], self.H.shape[0]
        self.B = np.zeros((n, 0)) if B is None else as_matrix(B, "B", (n, None), owner=own)
        self.m = self.B.shape[1]
        self.D = np.zeros((p, self.m)) if D is None else as_matrix(D, "D", (p, self.m), owner=own)
        self.x0 = np.zeros(n) if x0 is None else as_vector(x0, "x0", n, owner=own)
        self.state_names = tuple(state_names) if state_names is not None else tuple(f"x{i}" for i in range(n))
        self.n, self.p = n, p
        self.reset()

    def reset(self) -> None:
        """Back to ``x0``."""
        self.x = self.x0.copy()

    def predict(self, u=None) -> None:
        """:math:`x^- = F x^+ + B u`."""
        u = np.zeros(self.m) if u is None else as_vector(u, "u", self.m)
        self.x = self.F @ self.x + self.B @ u

    def update(self, z, u=None) -> None:
        """:math:`x^+ = x^- + K (z - H x^- - D u)`."""
        z = as_vector(z, "z", self.p)
        u = np.zeros(self.m) if u is None else as_vector(u, "u", self.m)
        self.x = self.x + self.gain.K @ (z - self.H @ self.x - self.D @ u)

    def filter(self, zs, us=None) -> KalmanResult:
        """Batch run from ``x0``: ``update(z[k], u[k])`` then ``predict(u[k])`` for each ``k``."""
        zs, us = _batch(zs, us, self.p, self.m, "SteadyStateKalmanFilter.filter")
        N, n = zs.shape[0], self.n
        x_prior, x_post, nu = np.empty((N, n)), np.empty((N, n)), np.empty((N, self.p))
        self.reset()
        for k in range(N):
            x_prior[k] = self.x
            nu[k] = zs[k] - self.H @ self.x - self.D @ us[k]
            self.update(zs[k], us[k])
            x_post[k] = self.x
            self.predict(us[k])
        g = self.gain
        S = self.H @ g.P @ self.H.T
        return KalmanResult(x_prior, np.broadcast_to(g.P, (N, n, n)), x_post, np.broadcast_to(g.P_post, (N, n, n)),
                            np.broadcast_to(g.K, (N, n, self.p)), nu, np.broadcast_to(S, (N, self.p, self.p)),
                            self.state_names)


class ContinuousObserver:
    """Continuous-time observer run at a fixed sampling period, eq. (8) of [1]_.

    .. math::

        \\dot{\\hat x} = A \\hat x + B u + L (y - C \\hat x - D u)
                      = (A - L C)\\hat x + (B - L D) u + L y

    discretised exactly under the assumption that ``u`` and ``y`` are held
    constant over each period ``dt`` (zero-order hold, matrix exponential):
    :math:`\\hat x_{k+1} = \\Phi \\hat x_k + \\Gamma_u u_k + \\Gamma_y y_k`.

    Parameters
    ----------
    A, B, C : array_like, shapes (n, n), (n, m), (p, n)
    L : array_like, shape (n, p)
        Observer gain, e.g. ``continuous_kalman_gain(...).L``.
    dt : float, s
        Sampling period.
    D : array_like, shape (p, m), optional
    x0 : array_like, shape (n,), optional
    state_names : sequence of str, optional

    Attributes
    ----------
    x : ndarray, shape (n,)
        Current estimate :math:`\\hat x_k`.
    Phi, Gamma_u, Gamma_y : ndarray
        The discretised observer.
    gain : ObserverGain or None
        The CARE design when built by :meth:`design`.
    """

    def __init__(self, A, B, C, L, *, dt: float, D=None, x0=None, state_names=None):
        own = "ContinuousObserver"
        A = as_matrix(A, "A", (None, None), owner=own)
        n = A.shape[0]
        B = as_matrix(B, "B", (n, None), owner=own)
        C = as_matrix(C, "C", (None, n), owner=own)
        p, m = C.shape[0], B.shape[1]
        D = np.zeros((p, m)) if D is None else as_matrix(D, "D", (p, m), owner=own)
        L = as_matrix(L, "L", (n, p), owner=own)
        self.A, self.B, self.C, self.D, self.L, self.dt = A, B, C, D, L, float(dt)
        self.Phi, G = zoh(A - L @ C, np.hstack([B - L @ D, L]), dt)
        self.Gamma_u, self.Gamma_y = G[:, :m], G[:, m:]
        self.x0 = np.zeros(n) if x0 is None else as_vector(x0, "x0", n, owner=own)
        self.state_names = tuple(state_names) if state_names is not None else tuple(f"x{i}" for i in range(n))
        self.n, self.p, self.m = n, p, m
        self.gain: ObserverGain | None = None  # set by design()
        self.reset()

    @classmethod
    def design(cls, A, B, C, Q, R, *, dt: float, D=None, G=None, x0=None, state_names=None):
        """Kalman-Bucy observer: ``L`` from :func:`continuous_kalman_gain`, then discretised at `dt`."""
        gain = continuous_kalman_gain(A, C, Q, R, G=G, state_names=state_names)
        obs = cls(A, B, C, gain.L, dt=dt, D=D, x0=x0, state_names=state_names)
        obs.gain = gain
        return obs

    def reset(self) -> None:
        """Back to ``x0``."""
        self.x = self.x0.copy()

    def output(self, u=None) -> np.ndarray:
        """Estimated output :math:`\\hat y_k = C \\hat x_k + D u_k`, shape (p,)."""
        u = np.zeros(self.m) if u is None else as_vector(u, "u", self.m)
        return self.C @ self.x + self.D @ u

    def step(self, u, y) -> np.ndarray:
        """Advance one period with ``u`` (shape (m,)) and measurement ``y`` (shape (p,)) held; return :math:`\\hat x_{k+1}`."""
        u = as_vector(u, "u", self.m, owner="ContinuousObserver")
        y = as_vector(y, "y", self.p, owner="ContinuousObserver")
        self.x = self.Phi @ self.x + self.Gamma_u @ u + self.Gamma_y @ y
        return self.x.copy()

    def run(self, us, ys) -> np.ndarray:
        """Batch: estimates :math:`\\hat x_k` for ``k = 0..N`` (shape (N + 1, n)) from ``x0``."""
        ys, us = _batch(ys, us, self.p, self.m, "ContinuousObserver.run")
        out = np.empty((ys.shape[0] + 1, self.n))
        self.reset()
        out[0] = self.x
        for k in range(ys.shape[0]):
            out[k + 1] = self.step(us[k], ys[k])
        return out
