"""Discrete PID and the Kalman-PID (KPID) of [1]_: :class:`PID`, :class:`KPID`,
and the "PID-inverse" model the KPID filter runs (:func:`kpid_model`,
:func:`kpid_model_zoh`).

Reading of [1]_ (Section 2) used here
-------------------------------------
- **Control law, eq. (14)** (both controllers, ``T`` the sampling period):

  .. math::

      u_k = K_p e_k + K_i T \\sum_{j=0}^{k} e_j + K_d \\frac{e_k - e_{k-1}}{T},
      \\qquad e_{-1} = 0

  with the error **reference minus output**: :math:`e = y_d - y` for the
  plain PID and :math:`e_2 = y_d - y_e` (filtered output) for KPID.  The
  paper's eq. (1) writes :math:`e_1 = y - y_d`, which with positive gains is
  positive feedback on a plant whose output rises with ``u`` (the PAM of
  eq. (15), DC gain +27.8); eq. (14) and the model (5) use the negative-
  feedback sign, and so do we.  The sum includes the current sample
  (rectangle rule); the derivative is the backward difference, so the first
  sample carries a derivative kick :math:`K_d e_0 / T` (no filtering: the
  paper has none).
- **Model, eqs. (4)-(5)**: the PID law read as the plant's inverse,
  :math:`u = PID(s)\\,(y_d - y)`, i.e.
  :math:`y - y_d = -s / (K_d s^2 + K_p s + K_i)\\, u`:

  .. math::

      \\dot x = \\begin{bmatrix} -K_p/K_d & -K_i/K_d \\\\ 1 & 0 \\end{bmatrix} x
              + \\begin{bmatrix} 1 \\\\ 0 \\end{bmatrix} u, \\qquad
      y = \\begin{bmatrix} -1/K_d & 0 \\end{bmatrix} x + y_d

  (eq. (3) prints the transfer function with the opposite sign; eq. (4b)'s
  :math:`-1/K_d` is the one consistent with eqs. (5) and (14)).  ``Kd`` and
  ``Ki`` must be non-zero, as the paper notes.
- **Discretisation, eqs. (6)-(7)**: the printed entries of (7) mix the
  over-damped (cosh/sinh) and under-damped (sin/cos) closed forms and carry
  :math:`e^{+T K_p / 2K_d}` where the decaying :math:`e^{-T K_p / 2K_d}` is
  meant, so they are not used: the model is discretised **exactly** by the
  zero-order hold, :math:`A_d = e^{AT}`, :math:`B_d = \\int_0^T e^{A\\tau}d\\tau B`,
  computed with the matrix exponential of the augmented matrix.
- **Filter, eqs. (8)-(13)**: :math:`P^- = A P^+ A^T + B Q B^T` (process noise
  on ``u``, eq. (8)), gain (9), :math:`P^+ = (I - M C) P^-` (10), prior (11)
  with the previous control :math:`u_{k-1}`.  Eq. (12) as printed,
  :math:`x^+ = A x^- + M (y_v - C A x^-)`, applies ``A`` a second time and
  omits the offset ``D = y_d``; we use the update consistent with (6) and
  (8)-(11): :math:`x^+ = x^- + M (y_v - C x^- - y_d)`, and (13)
  :math:`y_e = C x^+ + y_d`.  The covariance update uses the Joseph form
  (equal to (10) in exact arithmetic).  The paper does not give ``P(0)``;
  we take ``x(0) = 0`` and ``P(0) = 0`` (the controller starts at rest, known).

References
----------
.. [1] Yang H., Hao L., Chen Y., Xue B., "Kalman-PID control for chattering
   phenomena of bionic elbow joint actuated by pneumatic artificial muscles",
   Control Theory & Applications (2017); seed 002 (``docs/references.md``).
"""
from __future__ import annotations

import numpy as np

from estimators.errors import EstimatorError

from ._linalg import zoh

__all__ = ["PID", "KPID", "kpid_model", "kpid_model_zoh", "PAPER_SIMULATION"]

#: Section 3 of [1]_: gains, period and noise covariances of the simulation (Tables 1-2).
PAPER_SIMULATION = {"Kp": 25.0, "Ki": 1e-6, "Kd": 1e-3, "T": 1e-3, "Q": 1.0, "R": 1.0}


def _finite(value, name, owner, *, nonzero=False, positive=False) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise EstimatorError(f"{owner}: {name} must be a real number, got {value!r}", name=name) from None
    if not np.isfinite(v) or (nonzero and v == 0.0) or (positive and v <= 0.0):
        need = "> 0" if positive else "non-zero" if nonzero else "finite"
        raise EstimatorError(f"{owner}: {name} must be finite and {need}, got {v!r}", name=name)
    return v


def kpid_model(Kp: float, Ki: float, Kd: float):
    """Continuous model (5) of [1]_: the PID law read as the plant's inverse.

    Returns
    -------
    A : ndarray, shape (2, 2)
    B : ndarray, shape (2, 1)
    C : ndarray, shape (1, 2)
        ``y = C x + y_d``.
    """
    own = "kpid_model"
    Kp = _finite(Kp, "Kp", own)
    Ki, Kd = _finite(Ki, "Ki", own, nonzero=True), _finite(Kd, "Kd", own, nonzero=True)
    A = np.array([[-Kp / Kd, -Ki / Kd], [1.0, 0.0]])
    return A, np.array([[1.0], [0.0]]), np.array([[-1.0 / Kd, 0.0]])


def kpid_model_zoh(Kp: float, Ki: float, Kd: float, T: float):
    """Model (6) of [1]_ discretised exactly (zero-order hold, matrix exponential).

    Parameters
    ----------
    Kp, Ki, Kd : float
        PID gains (``Ki``, ``Kd`` non-zero).
    T : float, s
        Sampling period.

    Returns
    -------
    Ad : ndarray, shape (2, 2)
    Bd : ndarray, shape (2, 1)
    C : ndarray, shape (1, 2)
    """
    A, B, C = kpid_model(Kp, Ki, Kd)
    Ad, Bd = zoh(A, B, _finite(T, "T", "kpid_model_zoh", positive=True))
    return Ad, Bd, C


class PID:
    """Discrete PID of eq. (14) of [1]_: ``u = step(reference, measurement)``.

    Parameters
    ----------
    Kp : float
        Proportional gain (unit of u per unit of y).
    Ki : float
        Integral gain (per s).
    Kd : float
        Derivative gain (s).
    T : float, s
        Sampling period.

    Attributes
    ----------
    error_sum : float
        :math:`\\sum_{j \\le k} e_j` (unit of y).
    last_error : float
        :math:`e_{k-1}` (0 before the first step).

    Examples
    --------
    >>> pid = PID(2.0, 10.0, 0.01, T=0.01)
    >>> pid.step(1.0, 0.0)   # 2*1 + 10*0.01*1 + 0.01*(1 - 0)/0.01
    3.1
    """

    def __init__(self, Kp: float, Ki: float, Kd: float, *, T: float):
        own = type(self).__name__
        self.Kp, self.Ki, self.Kd = (_finite(v, n, own) for v, n in ((Kp, "Kp"), (Ki, "Ki"), (Kd, "Kd")))
        self.T = _finite(T, "T", own, positive=True)
        self.reset()

    def reset(self) -> None:
        """Error sum and previous error back to zero."""
        self.error_sum = 0.0
        self.last_error = 0.0

    def _law(self, e: float) -> float:
        # eq. (14): rectangle-rule sum including e_k, backward-difference derivative
        self.error_sum += e
        u = self.Kp * e + self.Ki * self.T * self.error_sum + self.Kd * (e - self.last_error) / self.T
        self.last_error = e
        return u

    def step(self, reference: float, measurement: float) -> float:
        """Control for this sample; error ``reference - measurement``."""
        return self._law(float(reference) - float(measurement))


class KPID(PID):
    """Kalman-PID of [1]_: the PID law (14) on the Kalman-filtered output (13).

    Each step: predict with the previous control (11), update with the
    measurement, :math:`y_e = C x^+ + y_d`, :math:`e_2 = y_d - y_e`, then the
    law (14).  See the module docstring for the reading of eqs. (6)-(13).

    Parameters
    ----------
    Kp, Ki, Kd : float
        PID gains (``Ki``, ``Kd`` non-zero: they divide in model (5)).
    T : float, s
        Sampling period.
    Q : float
        Variance of the process noise on ``u`` (eq. (8)), >= 0.
    R : float
        Variance of the measurement noise (eq. (9)), > 0.
    P0 : array_like, shape (2, 2), optional
        Initial covariance (zeros: not given by the paper).

    Attributes
    ----------
    A, B, C : ndarray
        Exact ZOH model (6).
    x : ndarray, shape (2,)
        Posterior state :math:`x^+_k`.
    P : ndarray, shape (2, 2)
    filtered : float
        :math:`y_e` of the last step (unit of y).
    gain : ndarray, shape (2, 1)
        Kalman gain ``M`` of the last step.
    """

    def __init__(self, Kp: float, Ki: float, Kd: float, *, T: float, Q: float, R: float, P0=None):
        super().__init__(Kp, Ki, Kd, T=T)
        self.A, self.B, self.C = kpid_model_zoh(self.Kp, self.Ki, self.Kd, self.T)
        self.Q = _finite(Q, "Q", "KPID")
        if self.Q < 0:
            raise EstimatorError(f"KPID: Q must be >= 0, got {self.Q}", name="Q")
        self.R = _finite(R, "R", "KPID", positive=True)
        self.P0 = np.zeros((2, 2)) if P0 is None else np.array(P0, dtype=float)
        if self.P0.shape != (2, 2) or not np.all(np.isfinite(self.P0)) or np.min(np.linalg.eigvalsh(
                0.5 * (self.P0 + self.P0.T))) < -1e-12 * max(1.0, np.abs(self.P0).max()):
            raise EstimatorError("KPID: P0 must be a finite symmetric PSD (2, 2) matrix", name="P0")
        self.reset()

    def reset(self) -> None:
        """Controller and filter back to rest."""
        super().reset()
        if hasattr(self, "P0"):
            self.x = np.zeros(2)
            self.P = self.P0.copy()
            self.last_u = 0.0
            self.filtered = 0.0
            self.gain = np.zeros((2, 1))

    def step(self, reference: float, measurement: float) -> float:
        """Control for this sample from the noisy measurement :math:`y_v`."""
        yd, yv = float(reference), float(measurement)
        A, B, C = self.A, self.B, self.C
        x = A @ self.x + B[:, 0] * self.last_u                  # eq. (11)
        P = A @ self.P @ A.T + self.Q * (B @ B.T)               # eq. (8)
        S = (C @ P @ C.T)[0, 0] + self.R
        M = P @ C.T / S                                         # eq. (9)
        x = x + M[:, 0] * (yv - C[0] @ x - yd)                 # eq. (12), consistent form
        IMC = np.eye(2) - M @ C
        P = IMC @ P @ IMC.T + self.R * (M @ M.T)                # eq. (10), Joseph form
        self.x, self.P, self.gain = x, 0.5 * (P + P.T), M
        self.filtered = float(C[0] @ x) + yd                    # eq. (13)
        u = self._law(yd - self.filtered)                       # e2 = y_d - y_e, eq. (14)
        self.last_u = u
        return u
