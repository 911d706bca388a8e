"""Linear discrete-time Kalman filter: :class:`KalmanFilter`, and its batch
result :class:`KalmanResult`.

Model (``k`` is the sample index, ``T`` the sampling period)

.. math::

    x_{k+1} = F x_k + B u_k + w_k, \\quad w_k \\sim N(0, Q), \\qquad
    z_k = H x_k + D u_k + v_k, \\quad v_k \\sim N(0, R).

The recursions are those of [1]_ (and of filterpy's ``KalmanFilter``, which
the tests match to 1e-10):

.. math::

    \\text{predict:}\\quad & x^- = F x^+ + B u, \\quad P^- = F P^+ F^T + Q \\\\
    \\text{update:}\\quad & \\nu = z - H x^- - D u, \\quad S = H P^- H^T + R, \\quad
        K = P^- H^T S^{-1} \\\\
    & x^+ = x^- + K \\nu, \\quad
      P^+ = (I - K H) P^- (I - K H)^T + K R K^T \\quad \\text{(Joseph form)}

The Joseph form keeps :math:`P^+` symmetric positive semi-definite for any
gain and under rounding, where the short form :math:`(I - KH)P^-` does not;
:math:`P^+` is then symmetrised exactly.  :math:`S^{-1}` is applied by a
Cholesky solve, never formed.

References
----------
.. [1] R. E. Kalman, "A new approach to linear filtering and prediction
   problems", J. Basic Eng. 82 (1960) 35-45; the Joseph form in
   R. S. Bucy and P. D. Joseph, *Filtering for Stochastic Processes*, 1968.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
import scipy.linalg

from estimators.errors import EstimatorError

from ._linalg import as_matrix, as_vector, check_covariance

__all__ = ["KalmanFilter", "KalmanResult"]


@dataclass(frozen=True)
class KalmanResult:
    """A filtered recording (one row per sample ``k``).

    Attributes
    ----------
    x_prior : ndarray, shape (N, n)
        :math:`x^-_k`, the estimate before measurement ``z[k]``.
    P_prior : ndarray, shape (N, n, n)
    x_post : ndarray, shape (N, n)
        :math:`x^+_k`, the estimate after measurement ``z[k]``.
    P_post : ndarray, shape (N, n, n)
    K : ndarray, shape (N, n, p)
        Kalman gains.
    innovation : ndarray, shape (N, p)
        :math:`\\nu_k = z_k - H x^-_k - D u_k`.
    S : ndarray, shape (N, p, p)
        Innovation covariances.
    state_names : tuple of str
    """

    x_prior: np.ndarray
    P_prior: np.ndarray
    x_post: np.ndarray
    P_post: np.ndarray
    K: np.ndarray
    innovation: np.ndarray
    S: np.ndarray
    state_names: tuple = ()


class KalmanFilter:
    """Time-invariant linear Kalman filter with optional known input.

    Parameters
    ----------
    F : array_like, shape (n, n)
        State transition matrix (one sampling period).
    H : array_like, shape (p, n)
        Measurement matrix.
    Q : array_like, shape (n, n)
        Process-noise covariance, symmetric positive semi-definite (units of
        x_i x_j per sample).
    R : array_like, shape (p, p)
        Measurement-noise covariance, symmetric positive definite.
    B : array_like, shape (n, m), optional
        Input matrix; without it the filter has no input (``m = 0``).
    D : array_like, shape (p, m), optional
        Feedthrough of the input into the measurement (needs `B` for ``m``).
    x0 : array_like, shape (n,), optional
        Prior mean at sample 0 (default zeros).
    P0 : array_like, shape (n, n), optional
        Prior covariance at sample 0, symmetric PSD (default identity).
    state_names : sequence of str, optional
        Names of the states (used in results and error messages).

    Attributes
    ----------
    x, P : ndarray
        Current estimate and covariance (posterior after :meth:`update`, prior
        after :meth:`predict`).
    x_prior, P_prior, x_post, P_post : ndarray
        The last prior and posterior.
    K, S, innovation : ndarray
        Of the last update.

    Raises
    ------
    EstimatorError
        Wrong shape or non-finite entry in any matrix; `Q` or `P0` not
        symmetric PSD; `R` not symmetric PD.  The message names the matrix.

    Examples
    --------
    >>> import numpy as np
    >>> kf = KalmanFilter([[1.0]], [[1.0]], Q=[[0.0]], R=[[1.0]], P0=[[1.0]])
    >>> kf.update([2.0])           # equal weight on prior 0 and measurement 2
    >>> round(float(kf.x[0]), 12), round(float(kf.P[0, 0]), 12)
    (1.0, 0.5)
    """

    def __init__(self, F, H, Q, R, *, B=None, D=None, x0=None, P0=None,
                 state_names: Sequence[str] | None = None):
        own = "KalmanFilter"
        self.F = as_matrix(F, "F", (None, None), owner=own)
        n = self.F.shape[0]
        if self.F.shape != (n, n):
            raise EstimatorError(f"{own}: F: expected a square matrix but found shape {self.F.shape}", name="F")
        self.H = as_matrix(H, "H", (None, n), owner=own)
        p = self.H.shape[0]
        self.B = np.zeros((n, 0)) if B is None else as_matrix(B, "B", (n, None), owner=own)
        m = self.B.shape[1]
        if D is not None and B is None:
            raise EstimatorError(f"{own}: D given without B; pass B (n, m) to define the input", name="D")
        self.D = np.zeros((p, m)) if D is None else as_matrix(D, "D", (p, m), owner=own)
        self.Q = check_covariance(Q, "Q", n, definite=False, owner=own)
        self.R = check_covariance(R, "R", p, definite=True, owner=own)
        self.x0 = np.zeros(n) if x0 is None else as_vector(x0, "x0", n, owner=own)
        self.P0 = np.eye(n) if P0 is None else check_covariance(P0, "P0", n, definite=False, owner=own)
        self.state_names = tuple(state_names) if state_names is not None else tuple(f"x{i}" for i in range(n))
        if len(self.state_names) != n:
            raise EstimatorError(f"{own}: {len(self.state_names)} state names for {n} states", name="state_names")
        self.n, self.p, self.m = n, p, m
        self._I = np.eye(n)
        self.reset()

    # -- state -------------------------------------------------------------
    def reset(self) -> None:
        """Back to the prior ``(x0, P0)`` at sample 0."""
        self.x = self.x0.copy()
        self.P = self.P0.copy()
        self.x_prior, self.P_prior = self.x.copy(), self.P.copy()
        self.x_post, self.P_post = self.x.copy(), self.P.copy()
        self.K = np.zeros((self.n, self.p))
        self.S = self.R.copy()
        self.innovation = np.zeros(self.p)

    def _input(self, u) -> np.ndarray:
        if u is None:
            return np.zeros(self.m)
        return as_vector(u, "u", self.m, owner="KalmanFilter")

    # -- recursions ----------------------------------------------------------
    def predict(self, u=None) -> None:
        """Time update over one sample: :math:`x^- = F x + B u`, :math:`P^- = F P F^T + Q`.

        Parameters
        ----------
        u : array_like, shape (m,), optional
            Input held over the sample (zeros when omitted).
        """
        u = self._input(u)
        self.x = self.F @ self.x + self.B @ u
        P = self.F @ self.P @ self.F.T + self.Q
        self.P = 0.5 * (P + P.T)
        self.x_prior, self.P_prior = self.x.copy(), self.P.copy()

    def update(self, z, u=None) -> None:
        """Measurement update with ``z`` (Joseph form).

        Parameters
        ----------
        z : array_like, shape (p,)
            Measurement, in the units of the rows of `H`.
        u : array_like, shape (m,), optional
            Input at this sample, for the feedthrough `D`.
        """
        z = as_vector(z, "z", self.p, owner="KalmanFilter")
        u = self._input(u)
        nu = z - self.H @ self.x - self.D @ u
        PHt = self.P @ self.H.T
        S = self.H @ PHt + self.R
        S = 0.5 * (S + S.T)
        # K = P H^T S^-1 by a Cholesky solve of S K^T = H P (S is SPD: R is PD)
        K = scipy.linalg.cho_solve(scipy.linalg.cho_factor(S), PHt.T).T
        self.x = self.x + K @ nu
        IKH = self._I - K @ self.H
        # Joseph form: PSD for any K, robust to rounding (Bucy & Joseph)
        P = IKH @ self.P @ IKH.T + K @ self.R @ K.T
        self.P = 0.5 * (P + P.T)
        self.K, self.S, self.innovation = K, S, nu
        self.x_post, self.P_post = self.x.copy(), self.P.copy()

    # -- batch -----------------------------------------------------------------
    def filter(self, zs, us=None) -> KalmanResult:
        """Run a recording from the prior ``(x0, P0)``: for each sample ``k``,
        ``update(z[k], u[k])`` then ``predict(u[k])``.

        So ``x0`` is the prior of sample 0, ``u[k]`` acts from sample ``k`` to
        ``k + 1`` (and through `D` on ``z[k]``).  The filter is reset first and
        left after the last prediction.

        Parameters
        ----------
        zs : array_like, shape (N, p)
            Measurements.
        us : array_like, shape (N, m), optional
            Inputs (zeros when omitted).

        Returns
        -------
        KalmanResult
        """
        zs = np.array(zs, dtype=float)
        if zs.ndim == 1 and self.p == 1:
            zs = zs[:, None]
        if zs.ndim != 2 or zs.shape[1] != self.p:
            raise EstimatorError(f"KalmanFilter.filter: zs: expected shape (N, {self.p}) but found {zs.shape}",
                                 name="zs")
        N = zs.shape[0]
        if us is None:
            us = np.zeros((N, self.m))
        us = np.array(us, dtype=float)
        if us.ndim == 1 and self.m == 1:
            us = us[:, None]
        if us.shape != (N, self.m):
            raise EstimatorError(f"KalmanFilter.filter: us: expected shape ({N}, {self.m}) but found {us.shape}",
                                 name="us")
        n, p = self.n, self.p
        out = dict(x_prior=np.empty((N, n)), P_prior=np.empty((N, n, n)), x_post=np.empty((N, n)),
                   P_post=np.empty((N, n, n)), K=np.empty((N, n, p)), innovation=np.empty((N, p)),
                   S=np.empty((N, p, p)))
        self.reset()
        for k in range(N):
            out["x_prior"][k], out["P_prior"][k] = self.x, self.P
            self.update(zs[k], us[k])
            out["x_post"][k], out["P_post"][k] = self.x, self.P
            out["K"][k], out["innovation"][k], out["S"][k] = self.K, self.innovation, self.S
            self.predict(us[k])
        return KalmanResult(state_names=self.state_names, **out)
