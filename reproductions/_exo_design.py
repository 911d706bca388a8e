"""Linear design of the ``exo-lqi`` scenario (Section 5.2 of [1]_): the
relative-angle exoskeleton model, the LQI gains of eqs. (12)-(17), the
Kalman observers and the continuous loops analysed for margins and bandwidth.

Relative angles
---------------
With the absolute angles of eq. (3) and the two sensors of eq. (5) (motor
velocity, sensor torque) turning every body together (``theta_m`` by
``r_g``) is invisible: eigenvalue 0, not detectable, no Kalman observer
(:func:`estimators.modes.check_detectable` says so).  We measure the angles
from the trunk instead:

.. math::

    x = [\\theta_m - r_g\\theta_h,\\ \\dot\\theta_m,\\ \\theta_{sint} - \\theta_h,\\
         \\dot\\theta_{sint},\\ \\theta_{sext} - \\theta_h,\\ \\dot\\theta_{sext}]^T

Every spring of eq. (1) sees an angle difference, so ``theta_h`` cancels and

.. math::

    \\dot x = A_1 x + B_m \\tau_m + B_h \\dot\\theta_h,\\qquad
    B_h = [-r_g, 0, -1, 0, -1, d_{eh}/J_{sext}]^T,\\qquad
    y_b = C_b x - d_{eh}\\dot\\theta_h

with :math:`A_1, B_m, C_b` exactly those of eqs. (4), (7) and (10): the
paper's LQI design (on ``A1``, which drops ``theta_h``) is the design of this
model, and ``(A1, [C_v; C_t])`` is observable.  ``theta_h_dot`` is a known
input of the observer, as in eq. (8).

Noise
-----
Sec. 4 gives bounds ``|w| <= a``; we draw uniform noise on ``[-a, a]``
(variance ``a^2 / 3``), held over each sample, and give the Kalman designs
those variances.  A Kalman gain depends only on the ratio of the process and
measurement covariances, so the continuous gain (eq. (9)) is the same for
sample variances or for the continuous intensities ``a^2 dt / 3``.

References
----------
.. [1] Exoskeleton bond graph / Kalman observer paper,
   seed 004 (``docs/references.md``), Sections 3-5, eqs. (3)-(17).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from types import MappingProxyType

import numpy as np
from scipy.signal import cont2discrete

from plants.blockdiagram.exoskeleton import state_space
from .errors import ParameterError
from plants.library.exoskeleton import parameter_values
from estimators.lqi import LQIGain, lqi
from estimators.observer import ObserverGain, continuous_kalman_gain, discrete_kalman_gain

__all__ = ["REL_STATES", "PAPER_SIMULATION_PARAMS", "NOISE_BOUNDS", "Q_PRIME_C", "R_PRIME_C", "Q_C", "R_C",
           "PAPER_GAINS", "ExoDesign", "design", "relative_model", "controller_system", "loop_at_plant_input",
           "disturbance_to_estimate", "sampled_loop_at_plant_input"]

REL_STATES = ("theta_m_rel", "dtheta_m", "theta_sint_rel", "dtheta_sint", "theta_sext_rel", "dtheta_sext")
#: Sec. 4 of [1]_: b_f, d_eh and d_s are neglected in the simulations.
PAPER_SIMULATION_PARAMS = MappingProxyType({"b_f": 0.0})
#: Sec. 4 of [1]_: bounds on w_tau_m (N m), w_theta_h_dot (rad/s), v_v (rad/s), v_t (N m).
NOISE_BOUNDS = MappingProxyType({"tau_m": 0.1e-3, "w_h": 0.15e-3, "w_m": 0.1e-6, "tau_s": 35e-3})
#: Eq. (14) (single integral action) and eq. (15) (double), units of x^2, z^2, w^2 per (N m)^2 of u.
Q_PRIME_C = (1e5, 1e5, 1e7, 1e7, 1e7, 1e7, 5e13)
R_PRIME_C = 1e12
Q_C = Q_PRIME_C + (5e15,)
R_C = 1e12
#: Eqs. (16)-(17) of [1]_ (F'_ix in the paper's printing order).
PAPER_GAINS = MappingProxyType({"Fix": (1.00, 0.03, 0.64, 0.0, 0.02, 0.0), "Fiz_prime": -3.16,
                                "Fiz": -70.71})


def relative_model(params):
    """The 6-state relative-angle model (module docstring) from eq. (3) of [1]_.

    Parameters
    ----------
    params : mapping str -> float
        Exoskeleton parameters (SI), as :func:`plants.library.exoskeleton.parameter_values`.

    Returns
    -------
    A1 : ndarray, shape (6, 6), 1/s and 1/s^2 entries
    Bm : ndarray, shape (6, 1), per N m
    Bh : ndarray, shape (6, 1), per rad/s of trunk velocity
    Cm : ndarray, shape (2, 6)
        Measured outputs ``[w_m (rad/s), tau_s (N m)]`` (eq. (5), y_v and y_t).
    Cb : ndarray, shape (1, 6)
        Body torque, N m (eq. (7)).
    """
    A, B, C, _ = state_space(params)
    A1, Bm = A[:6, :6], B[:6, [0]]
    Bh = np.array([[-params["r_g"], 0.0, -1.0, 0.0, -1.0, params["d_eh"] / params["J_sext"]]]).T
    return A1, Bm, Bh, C[[1, 0], :6], C[[2], :6]


@dataclass(frozen=True)
class ExoDesign:
    """Everything the scenario's controller needs, designed once.

    Attributes
    ----------
    params : dict str -> float
        Exoskeleton parameters (SI).
    dt : float, s
        Controller / observer period (and co-simulation step).
    A1, Bm, Bh, Cm, Cb : ndarray
        :func:`relative_model`.
    lqi2, lqi1 : LQIGain
        Double (eq. (15), used) and single (eq. (14), reported) integral action.
    observer_c : ObserverGain
        Continuous Kalman-Bucy gain, eq. (9) (margins, Bode).
    observer_d : ObserverGain
        Steady-state discrete Kalman filter of the ZOH model at `dt` (run in the loop).
    F, Gd : ndarray, shape (6, 6), (6, 2)
        ZOH discretisation of ``(A1, [Bm, Bh])`` at `dt`.
    noise_var : dict str -> float
        Variances ``a^2 / 3`` of the uniform noises (units squared).
    """

    params: dict
    dt: float
    A1: np.ndarray
    Bm: np.ndarray
    Bh: np.ndarray
    Cm: np.ndarray
    Cb: np.ndarray
    lqi2: LQIGain
    lqi1: LQIGain
    observer_c: ObserverGain
    observer_d: ObserverGain
    F: np.ndarray
    Gd: np.ndarray
    noise_var: dict = field(default_factory=dict)

    @property
    def d_eh(self) -> float:
        """Trunk-exoskeleton damping, N m s/rad (the ``-d_eh theta_h_dot`` term of eq. (6))."""
        return self.params["d_eh"]


def design(*, dt: float = 1e-4, params=None) -> ExoDesign:
    """Design the LQI (eqs. (12)-(15)) and the Kalman observers for period `dt` (s).

    Parameters
    ----------
    dt : float, s
        Controller period; must be positive and finite.
    params : mapping str -> float, optional
        Overrides of the library parameters on top of :data:`PAPER_SIMULATION_PARAMS`.

    Raises
    ------
    ParameterError
        `dt` not a positive finite number, or an unknown parameter name.
    """
    if not (isinstance(dt, (int, float)) and np.isfinite(dt) and dt > 0):
        raise ParameterError(f"exo-lqi design: dt must be a positive finite number of seconds; found {dt!r}",
                             name="dt")
    p = parameter_values({**PAPER_SIMULATION_PARAMS, **dict(params or {})})
    A1, Bm, Bh, Cm, Cb = relative_model(p)
    lqi2 = lqi(A1, Bm, Cb, np.diag(Q_C), [[R_C]], order=2, state_names=REL_STATES)
    lqi1 = lqi(A1, Bm, Cb, np.diag(Q_PRIME_C), [[R_PRIME_C]], order=1, state_names=REL_STATES)
    var = {k: a * a / 3.0 for k, a in NOISE_BOUNDS.items()}
    Qw = np.diag([var["tau_m"], var["w_h"]])
    Rv = np.diag([var["w_m"], var["tau_s"]])
    G = np.hstack([Bm, Bh])
    obs_c = continuous_kalman_gain(A1, Cm, Qw, Rv, G=G, state_names=REL_STATES)
    F, Gd, *_ = cont2discrete((A1, G, Cm, np.zeros((2, 2))), dt, method="zoh")
    # the noise is held over each sample, so it enters exactly through Gd
    obs_d = discrete_kalman_gain(F, Cm, Qw, Rv, G=Gd, state_names=REL_STATES)
    return ExoDesign(p, float(dt), A1, Bm, Bh, Cm, Cb, lqi2, lqi1, obs_c, obs_d, F, Gd, var)


def controller_system(d: ExoDesign):
    """The continuous controller of Fig. 12 of [1]_ from the measurements to the motor torque.

    Kalman-Bucy observer (eq. (8)) + double-integral LQI (eq. (13)), reference
    and trunk velocity set to zero:

    .. math::

        \\dot{\\hat x} = (A_1 - L C_m - B_m F'_{ix})\\hat x - B_m F'_{iz} z - B_m F_{iz} w + L y,\\quad
        \\dot z = -C_b \\hat x,\\quad \\dot w = z,\\quad
        u = -F'_{ix}\\hat x - F'_{iz} z - F_{iz} w

    Returns
    -------
    Ac : ndarray, shape (8, 8)
    Bc : ndarray, shape (8, 2)
        From ``y = [w_m, tau_s]``.
    Cc : ndarray, shape (1, 8)
        To ``u`` (N m).
    """
    g, L = d.lqi2, d.observer_c.L
    Ac = np.zeros((8, 8))
    Ac[:6, :6] = d.A1 - L @ d.Cm - d.Bm @ g.Kx
    Ac[:6, 6:7] = -d.Bm @ g.Kz
    Ac[:6, 7:8] = -d.Bm @ g.Kzz
    Ac[6, :6] = -d.Cb[0]
    Ac[7, 6] = 1.0
    Bc = np.zeros((8, 2))
    Bc[:6] = L
    Cc = -np.hstack([g.Kx, g.Kz, g.Kzz])
    return Ac, Bc, Cc


def loop_at_plant_input(d: ExoDesign):
    """Loop gain broken at the motor torque (P_in to P_out of Fig. 12 of [1]_).

    :math:`L(s) = -K(s) P(s)`, ``P`` the plant from ``tau_m`` to ``[w_m, tau_s]``
    and ``K`` :func:`controller_system`; negative-feedback convention, so the
    closed loop is stable iff ``1 + L`` has no zeros in the right half plane.

    Returns
    -------
    A, B, C, D : ndarray
        Series realisation, states ``[x (6), controller (8)]``; SISO.
    """
    Ac, Bc, Cc = controller_system(d)
    n = d.A1.shape[0]
    A = np.zeros((n + 8, n + 8))
    A[:n, :n] = d.A1
    A[n:, :n] = Bc @ d.Cm
    A[n:, n:] = Ac
    B = np.vstack([d.Bm, np.zeros((8, 1))])
    C = np.hstack([np.zeros((1, n)), -Cc])
    return A, B, C, np.zeros((1, 1))


def disturbance_to_estimate(d: ExoDesign):
    """Closed loop from the trunk velocity (rad/s) to the estimated body torque (N m), Fig. 15 of [1]_.

    States ``[x (6), x_hat (6), z, w]``, continuous observer, ``tau_ref = 0``.

    Returns
    -------
    A, B, C, D : ndarray
        ``B`` from ``theta_h_dot``; ``C`` rows: estimated ``y_b``, true ``y_b``.
    """
    Ac, Bc, Cc = controller_system(d)
    n = 6
    A = np.zeros((n + 8, n + 8))
    A[:n, :n] = d.A1
    A[:n, n:] = d.Bm @ Cc
    A[n:, :n] = Bc @ d.Cm
    A[n:, n:] = Ac
    B = np.zeros((n + 8, 1))
    B[:n] = d.Bh
    B[n:2 * n] = d.Bh                          # the observer knows theta_h_dot (eq. (8))
    C = np.zeros((2, n + 8))
    C[0, n:2 * n] = d.Cb[0]
    C[1, :n] = d.Cb[0]
    D = np.full((2, 1), -d.d_eh)               # eq. (6): y_b = Cb x - d_eh theta_h_dot
    return A, B, C, D


def sampled_loop_at_plant_input(d: ExoDesign):
    """The loop that runs in the co-simulation, broken at the motor torque: discrete, period ``d.dt``.

    Plant ``tau_m -> [w_m, tau_s]`` discretised with ZOH (``F``, ``Gd[:, 0]``,
    ``Cm``); controller the steady-state discrete Kalman filter (update form)
    and the LQI with forward-Euler integrators (:mod:`._exo_loop`):

    .. math::

        x^+ = (I - K C_m) x^- + K y,\\quad u = -F'_{ix} x^+ - F'_{iz} z - F_{iz} w,\\quad
        x^-_{+1} = F x^+ + G_{d,1} u,\\quad z_{+1} = z - dt\\, C_b x^+,\\quad w_{+1} = w + dt\\, z

    Returns
    -------
    A, B, C, D : ndarray
        Discrete loop gain ``L(z) = -K(z) P(z)``, states ``[x (6), x^- (6), z, w]``.
    """
    g, K, dt = d.lqi2, d.observer_d.K, d.dt
    n = 6
    IKC = np.eye(n) - K @ d.Cm
    kx = g.Kx[0]
    # controller (input y, output u): states [x_prior, z, w]
    Cc = np.concatenate([-kx @ IKC, [-g.Kz[0, 0], -g.Kzz[0, 0]]])[None, :]
    Dc = (-kx @ K)[None, :]
    Ac = np.zeros((n + 2, n + 2))
    Ac[:n, :n] = d.F @ IKC
    Ac[:n] += np.outer(d.Gd[:, 0], Cc[0])
    Ac[n, :n] = -dt * (d.Cb[0] @ IKC)
    Ac[n, n] = 1.0
    Ac[n + 1, n], Ac[n + 1, n + 1] = dt, 1.0
    Bc = np.zeros((n + 2, 2))
    Bc[:n] = d.F @ K + np.outer(d.Gd[:, 0], Dc[0])
    Bc[n] = -dt * (d.Cb[0] @ K)
    # series: plant (F, Gd[:, 0], Cm, 0) then controller; L = -u_out / u_in
    A = np.zeros((2 * n + 2, 2 * n + 2))
    A[:n, :n] = d.F
    A[n:, :n] = Bc @ d.Cm
    A[n:, n:] = Ac
    B = np.concatenate([d.Gd[:, 0], np.zeros(n + 2)])[:, None]
    C = -np.hstack([Dc @ d.Cm, Cc])
    return A, B, C, np.zeros((1, 1))
