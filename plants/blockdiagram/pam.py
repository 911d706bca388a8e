"""The antagonistic PAM joint's state-space model, eq. (11a) of [1]_, in plain numpy.

Written from the paper and the project's conventions [2]_ only, independently of
the bond graph in :mod:`plants.library.pam`, so that the two can be compared.
State, input and output (eqs. (1), (11a), (11b)):

.. math::

    x = [\\psi, \\dot\\psi, P_1, P_2]^T, \\qquad u = [u_1, u_2]^T, \\qquad
    y = [\\psi, P_1, P_2, \\tau]^T

    \\dot x = \\begin{bmatrix} \\dot\\psi \\\\
        (\\tau - T_f - k_s \\psi)/J \\\\
        k_1 R T m_1 / V_1 - k_2 (\\dot V_1 / V_1) P_1 \\\\
        k_1 R T m_2 / V_2 - k_2 (\\dot V_2 / V_2) P_2 \\end{bmatrix}, \\qquad
    \\tau = r \\cos\\psi \\, (F_1 - F_2)

with the muscle lengths of eq. (2) (:math:`l_{1,2} = L_0 \\mp r \\sin\\psi`), the
volumes of eq. (3), the valve flows of eq. (5), the contraction forces of
eqs. (6)-(7) and Kikuuwe's discrete-time friction, eq. (10).  Every reading of a
misprinted or ambiguous passage follows [2]_; each function says which.

Units: SI inside (rad, rad/s, Pa absolute, kg/s, N, N m); inputs in V; the only
non-SI output is ``psi_deg``.

References
----------
.. [1] T. Shin, T. Ibayashi, K. Kogiso, "Detailed dynamic model of antagonistic
   PAM system and its experimental validation: sensor-less angle and torque
   control with UKF", seed 000 (``docs/references.md``).
.. [2] "Antagonistic PAM joint (seed 000): the project's reference conventions",
   ``docs/pam-conventions.md``.
"""
from __future__ import annotations

import math
from types import SimpleNamespace
from typing import Mapping

import numpy as np

from ..errors import ArgumentError, ParameterError, SimulationError

__all__ = ["STATES", "INPUTS", "OUTPUTS", "VARIANTS", "PARAMS", "PARAM_UNITS", "KAPPA_U", "KAPPA_ALPHA",
           "SAMPLE_TIME", "SUBSTEPS", "DP_MIN", "kappa", "valve_mass_flow", "static_pressure", "equilibrium", "volume",
           "volume_rate", "muscle_lengths", "chamber_rates", "contraction_force", "joint_torque",
           "kikuuwe_friction", "derivatives", "simulate", "FIG8_SEGMENTS", "fig8_profile",
           "pressure_to_voltage"]

STATES = ("psi", "dpsi", "P1", "P2")          # rad, rad/s, Pa (abs), Pa (abs)
INPUTS = ("u1", "u2")                         # V, valve voltages
OUTPUTS = ("psi_deg", "P1", "P2", "tau")      # deg, Pa (abs), Pa (abs), N m -- eq. (11b)
VARIANTS = ("full", "frictionless", "locked")

SAMPLE_TIME = 1e-3      # s, sampling period of the rig (Sec. II-A of [1]); inputs held over it
SUBSTEPS = 4            # classic RK4 sub-steps per sample (conventions [2]): h = 0.25 ms
DP_MIN = 20e3           # Pa, lower clamp of P_i - P_out in T_p (conventions [2]; T_p diverges at P_out)

# Table II of [1], SI.  Names follow the paper; the index readings are those of [2].
PARAMS: dict[str, float] = {
    "r_p": 0.006,        # m, shaft radius (lever of the shaft friction T_s)
    "r": 0.0365,         # m, seesaw radius (eqs. (2), (9))
    "L0": 0.165,         # m, muscle length at psi = 0 (eq. (2))
    "M": 0.256,          # kg, seesaw mass (T_s)
    "g": 9.80,           # m/s^2, gravitational acceleration
    "P_tank": 0.7100e6,  # Pa abs, supply pressure (eq. (5))
    "P_out": 0.1013e6,   # Pa abs, atmospheric pressure (eq. (5), T_p)
    "k": 1.40,           # -, specific heat ratio of air (eq. (5))
    "R": 287.0,          # J/(kg K), gas constant of air (eqs. (4), (5))
    "T": 293.0,          # K, air temperature (eqs. (4), (5))
    "J": 4.263e-4,       # kg m^2, seesaw moment of inertia (eq. (8))
    "k_s": 4.117e-4,     # N m/rad, seesaw torque coefficient (eq. (8))
    "c_s": 2.256e-3,     # N m s/rad (Table II prints N s), viscous friction (eq. (10))
    "k1": 1.100,         # -, polytropic index on the flow term (eq. (4))
    "k2": 0.4545,        # -, polytropic index on the volume term (eq. (4))
    "D1": -2.440e-2,     # m, volume polynomial, l^2 coefficient (eq. (3))
    "D2": 6.824e-3,      # m^2, volume polynomial, l coefficient (eq. (3))
    "D3": -4.254e-4,     # m^3, volume polynomial, constant (eq. (3))
    "p_v11": 7.045e-3,   # m, muscle 1: slope of v(l) (eq. (7a)); last index = muscle [2]
    "p_v21": -1.017e-3,  # m^2, muscle 1: intercept of v(l) (eq. (7a))
    "p_w11": -556.8,     # N/m, muscle 1: slope of w(l) (eq. (7b))
    "p_w21": 72.86,      # N, muscle 1: intercept of w(l) (eq. (7b))
    "p_v12": 6.423e-3,   # m, muscle 2: slope of v(l) (eq. (7a))
    "p_v22": -9.184e-4,  # m^2, muscle 2: intercept of v(l) (eq. (7a))
    "p_w12": -197.8,     # N/m, muscle 2: slope of w(l) (eq. (7b))
    "p_w22": -15.75,     # N, muscle 2: intercept of w(l) (eq. (7b))
    "A1": 5.184e-8,      # m^2, filling orifice, A_0 when m > 0 (Table II "A_11"; both valves) [2]
    "A2": 7.776e-8,      # m^2, exhaust orifice, A_0 when m <= 0 (Table II "A_12"; both valves) [2]
    "mu_p": 4e8,         # N m Pa^2 (Table II "T'_p", printed (-)), tube Coulomb coefficient (T_p)
    "mu_s": 0.2,         # -, shaft Coulomb coefficient (T_s)
}

PARAM_UNITS: dict[str, str] = {
    "r_p": "m", "r": "m", "L0": "m", "M": "kg", "g": "m/s^2", "P_tank": "Pa", "P_out": "Pa", "k": "1",
    "R": "J/(kg K)", "T": "K", "J": "kg m^2", "k_s": "N m/rad", "c_s": "N m s/rad", "k1": "1", "k2": "1",
    "D1": "m", "D2": "m^2", "D3": "m^3", "p_v11": "m", "p_v21": "m^2", "p_w11": "N/m", "p_w21": "N",
    "p_v12": "m", "p_v22": "m^2", "p_w12": "N/m", "p_w22": "N", "A1": "m^2", "A2": "m^2",
    "mu_p": "N m Pa^2", "mu_s": "1",
}

# kappa(u) knots of [2] (V -> open rate alpha), built so that the static pressure is
# linear in u from P_out at 0 V to P_tank at 10 V (Fig. 5(c) of [1] gives kappa only as a figure)
KAPPA_U = tuple(0.5 * i for i in range(21))
KAPPA_ALPHA = (0.0, 0.1378, 0.1828, 0.2134, 0.2390, 0.2631, 0.2856, 0.3069, 0.3269, 0.3458, 0.3645,
               0.3844, 0.4057, 0.4288, 0.4545, 0.4835, 0.5174, 0.5589, 0.6134, 0.6962, 1.0)
_KU, _KA = np.asarray(KAPPA_U), np.asarray(KAPPA_ALPHA)


def _resolve(params: Mapping[str, float] | None) -> dict[str, float]:
    """PARAMS overridden by `params`; unknown names and non-finite values raise ParameterError."""
    if params is None or params is PARAMS:
        return PARAMS
    unknown = sorted(set(params) - set(PARAMS))
    if unknown:
        raise ParameterError(f"pam block diagram: unknown parameter(s) {', '.join(unknown)}; "
                             f"expected some of {', '.join(PARAMS)}", name=unknown[0])
    p = dict(PARAMS)
    for name, value in params.items():
        value = float(value)
        if not np.isfinite(value):
            raise ParameterError(f"pam block diagram: parameter {name} = {value} is not finite", name=name)
        p[name] = value
    return p


def _check_muscle(muscle: int) -> int:
    if muscle not in (1, 2):
        raise ArgumentError(f"muscle must be 1 or 2, got {muscle!r}")
    return muscle


def kappa(u):
    """Open rate :math:`\\alpha = \\kappa(u)` of a valve (Sec. II-B2 of [1]_, knots of [2]_).

    Parameters
    ----------
    u : float or ndarray, V
        Valve voltage; clipped to [0, 10].

    Returns
    -------
    alpha : float or ndarray, same shape as `u`, in [0, 1]

    Examples
    --------
    >>> float(kappa(5.0)), float(kappa(12.0)), float(kappa(0.25))
    (0.3645, 1.0, 0.0689)
    """
    return np.interp(np.clip(u, 0.0, 10.0), _KU, _KA)


# Two backends for one set of equations (:class:`_Plant`): NumPy ufuncs for batches and
# the public functions, Python floats for the simulation loop (NumPy scalars are ~10x slower).
_NP = SimpleNamespace(sqrt=np.sqrt, sin=np.sin, cos=np.cos, abs=np.abs, maximum=np.maximum,
                      minimum=np.minimum, sign=np.sign, where=np.where)
_FLOAT = SimpleNamespace(sqrt=math.sqrt, sin=math.sin, cos=math.cos, abs=abs, maximum=max, minimum=min,
                         sign=lambda v: (v > 0.0) - (v < 0.0), where=lambda c, a, b: a if c else b)


class _Plant:
    """Resolved parameters and the constants derived from them, computed once.

    Every method takes ``o``, the backend (:data:`_NP` or :data:`_FLOAT`).
    """

    def __init__(self, p: Mapping[str, float]):
        self.p = p
        k, R, T = p["k"], p["R"], p["T"]
        # orifice law of [2]: critical pressure ratio, sub-critical coefficient (1/sqrt(T) folded in)
        self.x_crit = (2.0 / (k + 1.0)) ** (k / (k - 1.0))
        self.phi_sub = math.sqrt(2.0 * k / (R * (k - 1.0))) / math.sqrt(T)
        self.e1 = 1.0 / k
        self.k1RT = p["k1"] * R * T
        # eq. (7): (p_v1i, p_v2i, p_w1i, p_w2i), the LAST index being the muscle i [2]
        self.force_coef = {i: (p[f"p_v1{i}"], p[f"p_v2{i}"], p[f"p_w1{i}"], p[f"p_w2{i}"]) for i in (1, 2)}

    def flux(self, P_a, P_b, o):
        """Signed mass flux a -> b per unit orifice area, kg/(s m^2); upstream = higher pressure [2]."""
        up, down = o.maximum(P_a, P_b), o.minimum(P_a, P_b)
        # choked below the critical ratio: P_up sqrt(k/R) (2/(k+1))^((k+1)/(2(k-1))) / sqrt(T) is the
        # sub-critical law's value (and maximum) AT x_crit, so clamping x gives both branches at once
        x = o.maximum(down / up, self.x_crit)
        y = x ** self.e1                                  # x^(1/k); x^((k-1)/k) = x / y
        return o.sign(P_a - P_b) * up * self.phi_sub * y * o.sqrt(o.maximum(1.0 - x / y, 0.0))

    def net_flow(self, alpha, P, o):
        p = self.p
        # eq. (5) per unit area: m_in tank -> muscle, m_out muscle -> atmosphere, both signed
        m = alpha * self.flux(p["P_tank"], P, o) - (1.0 - alpha) * self.flux(P, p["P_out"], o)
        # A_0 = A1 when filling, A2 otherwise; the sign of m does not depend on A_0 [2]
        return o.where(m > 0.0, p["A1"], p["A2"]) * m

    def lengths(self, psi, dpsi, o):
        # eq. (2) with Delta L = r sin(psi), and its time derivative
        r, L0 = self.p["r"], self.p["L0"]
        dl, dl_dot = r * o.sin(psi), r * o.cos(psi) * dpsi
        return L0 - dl, L0 + dl, -dl_dot, dl_dot

    def volume(self, l):
        return (self.p["D1"] * l + self.p["D2"]) * l + self.p["D3"]          # eq. (3)

    def volume_rate(self, l, l_dot):
        return (2.0 * self.p["D1"] * l + self.p["D2"]) * l_dot                 # d/dt of eq. (3)

    def chamber(self, P, m, V, V_dot):
        return (self.k1RT * m - self.p["k2"] * V_dot * P) / V                  # eq. (4)

    def force(self, P, l, i):
        pv1, pv2, pw1, pw2 = self.force_coef[i]
        return (pv1 * l + pv2) * P + pw1 * l + pw2                             # eqs. (6)-(7)

    def mechanics(self, psi, dpsi, P1, P2, o):
        l1, l2, l1_dot, l2_dot = self.lengths(psi, dpsi, o)
        F1, F2 = self.force(P1, l1, 1), self.force(P2, l2, 2)
        return l1, l2, l1_dot, l2_dot, F1, F2, self.p["r"] * o.cos(psi) * (F1 - F2)   # eq. (9)

    def friction(self, psi, dpsi, P1, P2, h, o):
        p = self.p
        F1, F2, tau = self.mechanics(psi, dpsi, P1, P2, o)[4:]
        Z = h / p["J"]                       # (rad/s)/(N m); eq. (10) prints Z = J/T_stp [2]
        T0 = tau - p["k_s"] * psi            # torque except friction
        w = dpsi + Z * T0                    # velocity after an implicit-Euler step without friction
        T_s = p["r_p"] * p["mu_s"] * o.abs(F1 + F2 - p["M"] * p["g"])
        d1 = o.maximum(P1 - p["P_out"], DP_MIN)      # clamp: T_p diverges at P_out [2]
        d2 = o.maximum(P2 - p["P_out"], DP_MIN)
        Fc = T_s + p["mu_p"] * (1.0 / (d1 * d1) + 1.0 / (d2 * d2))
        c_s = p["c_s"]
        return o.where(o.abs(w) > Z * Fc, (Fc * o.sign(w) + c_s * w) / (1.0 + Z * c_s), w / Z)

    def rates(self, psi, dpsi, P1, P2, a1, a2, T_f, o):
        p = self.p
        l1, l2, l1_dot, l2_dot, _, _, tau = self.mechanics(psi, dpsi, P1, P2, o)
        return (dpsi,
                (tau - p["k_s"] * psi - T_f) / p["J"],                                  # eq. (8)
                self.chamber(P1, self.net_flow(a1, P1, o), self.volume(l1), self.volume_rate(l1, l1_dot)),
                self.chamber(P2, self.net_flow(a2, P2, o), self.volume(l2), self.volume_rate(l2, l2_dot)))


def _plant(params) -> _Plant:
    return _Plant(_resolve(params))


def _columns(x):
    x = np.asarray(x, dtype=float)
    if x.shape[-1:] != (4,):
        raise ArgumentError(f"x must have shape (..., 4) (psi, dpsi, P1, P2), found {x.shape}")
    return x[..., 0], x[..., 1], x[..., 2], x[..., 3]


def valve_mass_flow(u, P, params=None, muscle: int = 1):
    """Mass flow of a valve into its muscle, eq. (5) of [1]_ with the orifice law of [2]_.

    .. math::

        m = A_0 \\big(\\alpha\\, \\phi(P_{tank}, P) - (1 - \\alpha)\\, \\phi(P, P_{out})\\big),
        \\quad \\alpha = \\kappa(u), \\quad
        A_0 = \\begin{cases} A_1 & \\text{if } m > 0 \\\\ A_2 & \\text{otherwise} \\end{cases}

        \\phi(P_a, P_b) = \\operatorname{sgn}(P_a - P_b) \\frac{P_{up}}{\\sqrt{T}}
        \\begin{cases} \\sqrt{k/R}\\,\\big(\\frac{2}{k+1}\\big)^{\\frac{k+1}{2(k-1)}}
            & x \\le \\big(\\frac{2}{k+1}\\big)^{\\frac{k}{k-1}} \\\\
        \\sqrt{\\frac{2k}{R(k-1)}}\\, x^{1/k} \\sqrt{1 - x^{(k-1)/k}} & \\text{otherwise} \\end{cases}

    with :math:`P_{up} = \\max(P_a, P_b)` and :math:`x = \\min(P_a, P_b)/P_{up}`:
    the flow reverses with the same law when the pressures do.

    Parameters
    ----------
    u : float or ndarray, V
        Valve voltage (clipped to [0, 10]).
    P : float or ndarray, Pa (absolute)
        Muscle pressure; broadcast against `u`.
    params : mapping str -> float, optional
        Overrides of :data:`PARAMS`.
    muscle : {1, 2}
        Which valve.  Both valves have the same orifices A1, A2 [2]_.

    Returns
    -------
    m : ndarray, kg/s
        Positive into the muscle.
    """
    _check_muscle(muscle)
    return _plant(params).net_flow(kappa(u), np.asarray(P, dtype=float), _NP)


def static_pressure(u, params=None):
    """Pressure at which a valve's flow vanishes, :math:`\\alpha m_{in} = (1-\\alpha) m_{out}`
    (proof of Proposition 1 of [1]_); independent of A1, A2.  Found by bisection.

    Parameters
    ----------
    u : float or ndarray, V
    params : mapping str -> float, optional

    Returns
    -------
    P : ndarray, same shape as `u`, Pa (absolute)
    """
    plant = _plant(params)
    alpha = kappa(np.asarray(u, dtype=float))
    lo, hi = np.full_like(alpha, plant.p["P_out"]), np.full_like(alpha, plant.p["P_tank"])
    for _ in range(60):     # the flow decreases monotonically in P; 60 halvings reach rounding
        mid = 0.5 * (lo + hi)
        filling = plant.net_flow(alpha, mid, _NP) > 0.0
        lo, hi = np.where(filling, mid, lo), np.where(filling, hi, mid)
    return 0.5 * (lo + hi)


def equilibrium(u, params=None, *, variant="full"):
    """Rest state for constant inputs `u`: static pressures and the angle where :math:`T_0 = 0`.

    .. math:: m_i(\\bar P_i) = 0, \\qquad
        r\\cos\\bar\\psi\\,(F_1 - F_2) - k_s\\bar\\psi = 0 \\quad (\\bar\\psi = 0 \\text{ if locked})

    Friction holds any angle with :math:`|T_0| \\le T_s + T_p`; this is the one
    without friction torque.  Found by bisection on :math:`|\\psi| \\le 0.6` rad (the
    muscle volumes of eq. (3) vanish near 35 deg).

    Parameters
    ----------
    u : array_like, shape (2,), V
    params : mapping str -> float, optional
    variant : {"full", "frictionless", "locked"}

    Returns
    -------
    x : ndarray, shape (4,)
        ``(psi [rad], 0, P1 [Pa], P2 [Pa])``.
    """
    if variant not in VARIANTS:
        raise ArgumentError(f"unknown variant {variant!r}; expected one of {', '.join(VARIANTS)}")
    plant = _plant(params)
    P1, P2 = static_pressure(np.asarray(u, dtype=float).reshape(2), params)
    x = np.array([0.0, 0.0, P1, P2])
    if variant == "locked":
        return x

    def T0(psi):
        return plant.mechanics(psi, 0.0, P1, P2, _FLOAT)[-1] - plant.p["k_s"] * psi

    lo, hi = -0.6, 0.6
    if T0(lo) * T0(hi) > 0.0:
        raise ArgumentError(f"no rest angle within +-0.6 rad for u = {u} (P1 = {P1:.0f} Pa, P2 = {P2:.0f} Pa)")
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if T0(mid) * T0(lo) > 0.0 else (lo, mid)
    x[0] = 0.5 * (lo + hi)
    return x


def pressure_to_voltage(P, params=None):
    """Voltage whose static pressure is `P` under the linear design of :func:`kappa` [2]_.

    .. math:: u = 10\\,(P - P_{out}) / (P_{tank} - P_{out})

    Parameters
    ----------
    P : float or ndarray, Pa (absolute)
    params : mapping str -> float, optional

    Returns
    -------
    u : ndarray, V
    """
    p = _resolve(params)
    return 10.0 * (np.asarray(P, dtype=float) - p["P_out"]) / (p["P_tank"] - p["P_out"])


def volume(l, params=None):
    """Muscle volume, eq. (3) of [1]_: :math:`V = D_1 l^2 + D_2 l + D_3`.

    Parameters
    ----------
    l : float or ndarray, m
    params : mapping str -> float, optional

    Returns
    -------
    V : float or ndarray, m^3
    """
    return _plant(params).volume(np.asarray(l, dtype=float))


def volume_rate(l, l_dot, params=None):
    """Time derivative of eq. (3) of [1]_: :math:`\\dot V = (2 D_1 l + D_2)\\, \\dot l`.

    Parameters
    ----------
    l : float or ndarray, m
    l_dot : float or ndarray, m/s
    params : mapping str -> float, optional

    Returns
    -------
    V_dot : float or ndarray, m^3/s
    """
    return _plant(params).volume_rate(np.asarray(l, dtype=float), np.asarray(l_dot, dtype=float))


def muscle_lengths(psi, dpsi, params=None):
    """Muscle lengths and their rates, eq. (2) of [1]_ with :math:`\\Delta L = r \\sin\\psi`.

    .. math::

        l_1 = L_0 - r\\sin\\psi, \\quad l_2 = L_0 + r\\sin\\psi, \\quad
        \\dot l_1 = -r\\cos\\psi\\,\\dot\\psi, \\quad \\dot l_2 = r\\cos\\psi\\,\\dot\\psi

    Parameters
    ----------
    psi : float or ndarray, rad
    dpsi : float or ndarray, rad/s
    params : mapping str -> float, optional

    Returns
    -------
    l1, l2 : ndarray, m
    l1_dot, l2_dot : ndarray, m/s
    """
    return _plant(params).lengths(np.asarray(psi, dtype=float), np.asarray(dpsi, dtype=float), _NP)


def chamber_rates(P, m, V, V_dot, params=None):
    """Pressure rate of a chamber, eq. (4) of [1]_ (T = 293 K [2]_).

    .. math:: \\dot P = k_1 \\frac{R T}{V} m - k_2 \\frac{\\dot V}{V} P

    Parameters
    ----------
    P : float or ndarray, Pa (absolute)
    m : float or ndarray, kg/s (into the muscle)
    V : float or ndarray, m^3
    V_dot : float or ndarray, m^3/s
    params : mapping str -> float, optional

    Returns
    -------
    P_dot : float or ndarray, Pa/s
    """
    return _plant(params).chamber(*(np.asarray(v, dtype=float) for v in (P, m, V, V_dot)))


def contraction_force(P, l, muscle: int, params=None):
    """Contraction force of muscle `muscle`, eqs. (6)-(7) of [1]_.

    .. math::

        F = v(l) P + w(l), \\quad v = p_{v1i} l + p_{v2i}, \\quad w = p_{w1i} l + p_{w2i}

    The LAST index ``i`` of the Table II names is the muscle [2]_.

    Parameters
    ----------
    P : float or ndarray, Pa (absolute)
    l : float or ndarray, m
    muscle : {1, 2}
    params : mapping str -> float, optional

    Returns
    -------
    F : ndarray, N
    """
    return _plant(params).force(np.asarray(P, dtype=float), np.asarray(l, dtype=float), _check_muscle(muscle))


def joint_torque(x, params=None):
    """Joint torque of the muscles, eq. (9) and output row 4 of eq. (11b) of [1]_.

    .. math:: \\tau = r \\cos\\psi\\,(F_1(P_1, l_1) - F_2(P_2, l_2))

    Parameters
    ----------
    x : ndarray, shape (..., 4)
        States ``(psi [rad], dpsi [rad/s], P1 [Pa], P2 [Pa])``.
    params : mapping str -> float, optional

    Returns
    -------
    tau : ndarray, shape (...), N m
    """
    return _plant(params).mechanics(*_columns(x), _NP)[-1]


def kikuuwe_friction(x, params=None, h: float = SAMPLE_TIME / SUBSTEPS):
    """Friction torque of eq. (10) of [1]_ (Kikuuwe et al.), as read in [2]_.

    .. math::

        Z = h / J, \\quad T_0 = \\tau - k_s\\psi, \\quad w = \\dot\\psi + Z T_0, \\quad
        F_c = T_s + T_p

        T_f = \\begin{cases} \\dfrac{F_c \\operatorname{sgn}(w) + c_s w}{1 + Z c_s} & |w| > Z F_c \\\\
        w / Z & |w| \\le Z F_c \\end{cases}

        T_s = r_p \\mu_s |F_1 + F_2 - M g|, \\quad
        T_p = \\mu_p \\Big(\\frac{1}{\\max(P_1 - P_{out}, 20\\,\\mathrm{kPa})^2}
              + \\frac{1}{\\max(P_2 - P_{out}, 20\\,\\mathrm{kPa})^2}\\Big)

    :math:`w` is the velocity an implicit-Euler step of length ``h`` reaches without
    friction.  Sticking (:math:`|w| \\le Z F_c`), :math:`T_f = T_0 + J\\dot\\psi/h`
    cancels the driving torque and brings the velocity to rest within the step.

    Parameters
    ----------
    x : ndarray, shape (..., 4)
        States ``(psi [rad], dpsi [rad/s], P1 [Pa], P2 [Pa])``.
    params : mapping str -> float, optional
    h : float, s
        Integration step the friction is held over (default 0.25 ms, the RK4 sub-step).

    Returns
    -------
    T_f : ndarray, shape (...), N m
    """
    return _plant(params).friction(*_columns(x), h, _NP)


def derivatives(x, u, params=None, T_f=0.0):
    """Right-hand side of the state-space model, eq. (11a) of [1]_.

    .. math::

        \\dot x = \\big[\\dot\\psi,\\; (\\tau - k_s\\psi - T_f)/J,\\;
        k_1 R T m_1/V_1 - k_2 (\\dot V_1/V_1) P_1,\\;
        k_1 R T m_2/V_2 - k_2 (\\dot V_2/V_2) P_2\\big]^T

    with :math:`l_{1,2} = L_0 \\mp r\\sin\\psi`, :math:`V_i = D_1 l_i^2 + D_2 l_i + D_3`,
    :math:`\\dot V_i = (2 D_1 l_i + D_2)\\,\\dot l_i`, :math:`m_i` of
    :func:`valve_mass_flow` and :math:`\\tau` of :func:`joint_torque`.  Eq. (11a)
    prints :math:`k_2 (V/V) P`: the dot of eq. (4) is lost in print.

    Parameters
    ----------
    x : ndarray, shape (..., 4)
        States ``(psi [rad], dpsi [rad/s], P1 [Pa], P2 [Pa])``; batches broadcast.
    u : ndarray, shape (..., 2), V
        Valve voltages ``(u1, u2)``.
    params : mapping str -> float, optional
    T_f : float or ndarray, shape (...), N m
        Friction torque (from :func:`kikuuwe_friction`, held by the caller).

    Returns
    -------
    dx : ndarray, shape (..., 4)
        ``(rad/s, rad/s^2, Pa/s, Pa/s)``.
    """
    alpha = kappa(np.asarray(u, dtype=float))
    if alpha.shape[-1:] != (2,):
        raise ArgumentError(f"u must have shape (..., 2) (u1, u2), found {alpha.shape}")
    rates = _plant(params).rates(*_columns(x), alpha[..., 0], alpha[..., 1], T_f, _NP)
    return np.stack(np.broadcast_arrays(*rates), axis=-1)


def _integrate(plant: _Plant, alphas: np.ndarray, x0: np.ndarray, variant: str) -> np.ndarray:
    """The fixed-step scheme of [2]: per sample, SUBSTEPS classic RK4 steps with the input
    held and T_f evaluated at each sub-step's start and held over it.  Float backend."""
    o, rates, friction = _FLOAT, plant.rates, plant.friction
    h = SAMPLE_TIME / SUBSTEPS
    h2, h6 = 0.5 * h, h / 6.0
    full = variant == "full"
    g = 0.0 if variant == "locked" else 1.0      # locked: psi'' = 0 in every stage, so psi = dpsi = 0
    out = np.empty((len(alphas) + 1, 4))
    out[0] = x0
    psi, dpsi, P1, P2 = (float(v) for v in x0)
    for k, (a1, a2) in enumerate(alphas.tolist()):
        for _ in range(SUBSTEPS):
            T_f = friction(psi, dpsi, P1, P2, h, o) if full else 0.0
            k1 = rates(psi, dpsi, P1, P2, a1, a2, T_f, o)
            k2 = rates(psi + h2 * k1[0], dpsi + g * h2 * k1[1], P1 + h2 * k1[2], P2 + h2 * k1[3], a1, a2, T_f, o)
            k3 = rates(psi + h2 * k2[0], dpsi + g * h2 * k2[1], P1 + h2 * k2[2], P2 + h2 * k2[3], a1, a2, T_f, o)
            k4 = rates(psi + h * k3[0], dpsi + g * h * k3[1], P1 + h * k3[2], P2 + h * k3[3], a1, a2, T_f, o)
            psi += h6 * (k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0])
            dpsi += g * h6 * (k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1])
            P1 += h6 * (k1[2] + 2.0 * k2[2] + 2.0 * k3[2] + k4[2])
            P2 += h6 * (k1[3] + 2.0 * k2[3] + 2.0 * k3[3] + k4[3])
        out[k + 1] = psi, dpsi, P1, P2
    return out


def simulate(u_profile, T, *, variant="full", x0=None, params=None) -> dict:
    """Simulate eq. (11a) of [1]_ with the fixed-step scheme of [2]_.

    Each sample ``[t_k, t_k + 1 ms)`` holds ``u_profile[k]`` (zero-order hold) and is
    integrated by 4 classic RK4 sub-steps of ``h = 0.25 ms``; the friction torque of
    :func:`kikuuwe_friction` (with that ``h``) is evaluated at the start of each
    sub-step and held over it.

    Parameters
    ----------
    u_profile : ndarray, shape (n_samples, 2), V
        Valve voltages ``(u1, u2)`` at ``t_k = k * 1 ms``; at least ``round(T / 1 ms)``
        rows (extra rows are ignored).  Clipped to [0, 10] by :func:`kappa`.
    T : float, s
        Horizon; a whole number of 1 ms samples.
    variant : {"full", "frictionless", "locked"}
        ``"frictionless"``: :math:`T_f \\equiv 0`; ``"locked"``: :math:`\\psi \\equiv
        \\dot\\psi \\equiv 0`, only the pressures evolve (the torque tests of [1]_).
    x0 : ndarray, shape (4,), optional
        Initial ``(psi [rad], dpsi [rad/s], P1 [Pa], P2 [Pa])``; default
        ``(0, 0, P_out, P_out)`` (joint at rest, muscles vented).
    params : mapping str -> float, optional
        Overrides of :data:`PARAMS`.

    Returns
    -------
    dict str -> ndarray, shape (n_samples + 1,)
        ``t`` (s), ``psi_deg`` (deg), ``P1``, ``P2`` (Pa abs), ``tau`` (N m, eq. (11b)),
        and ``x`` (shape (n_samples + 1, 4), the SI states).

    Raises
    ------
    SimulationError
        If a state stops being finite (its ``time`` is the first bad sample).
    """
    if variant not in VARIANTS:
        raise ArgumentError(f"unknown variant {variant!r}; expected one of {', '.join(VARIANTS)}")
    plant = _plant(params)
    n = int(round(T / SAMPLE_TIME))
    if n < 1 or abs(n * SAMPLE_TIME - T) > 1e-9:
        raise ArgumentError(f"T must be a positive whole number of {SAMPLE_TIME} s samples, got {T!r}")
    u = np.asarray(u_profile, dtype=float)
    if u.ndim != 2 or u.shape[1] != 2 or u.shape[0] < n:
        raise ArgumentError(f"u_profile must have shape (n_samples >= {n}, 2), found {u.shape}")
    p = plant.p
    x = np.array([0.0, 0.0, p["P_out"], p["P_out"]]) if x0 is None else np.array(x0, dtype=float)
    if x.shape != (4,):
        raise ArgumentError(f"x0 must have shape (4,), found {x.shape}")
    if variant == "locked" and (x[0] != 0.0 or x[1] != 0.0):
        raise ArgumentError(f"the locked variant holds psi = dpsi = 0; x0 has psi = {x[0]}, dpsi = {x[1]}")
    with np.errstate(all="ignore"):
        try:
            xs = _integrate(plant, kappa(u[:n]), x, variant)
        except (ArithmeticError, ValueError) as exc:      # float backend: math domain, division by 0
            raise SimulationError(f"pam block diagram: {exc}") from exc
    bad = ~np.all(np.isfinite(xs), axis=1)
    if bad.any():
        k = int(np.argmax(bad))
        raise SimulationError(f"pam block diagram: non-finite state at t = {k * SAMPLE_TIME:g} s", time=k * SAMPLE_TIME)
    return {"t": np.arange(n + 1) * SAMPLE_TIME, "psi_deg": np.degrees(xs[:, 0]), "P1": xs[:, 2].copy(),
            "P2": xs[:, 3].copy(), "tau": plant.mechanics(*_columns(xs), _NP)[-1], "x": xs}


# Fig. 8-like schedule: (kind, P1 [kPa abs], P2 [kPa abs]) per segment; "step" jumps to the
# pressures and holds them, "ramp" moves linearly from the previous pressures to them
FIG8_SEGMENTS = (
    ("step", 300.0, 450.0), ("ramp", 600.0, 450.0), ("step", 400.0, 700.0), ("ramp", 400.0, 300.0),
    ("step", 200.0, 600.0), ("ramp", 200.0, 700.0), ("ramp", 700.0, 700.0), ("step", 700.0, 400.0),
    ("ramp", 500.0, 500.0), ("step", 300.0, 300.0), ("ramp", 550.0, 650.0), ("step", 350.0, 500.0),
    ("ramp", 200.0, 250.0),
)


def fig8_profile(*, segment: float = 10.0, params=None):
    """A Fig. 8-like input profile: steps and ramps of u1, u2 over 200-700 kPa.

    Fig. 8 of [1]_ (the inputs of the offline and online estimations, N = 130e3
    samples of 1 ms) is given only as a plot "that cover[s] a wide pressure range of
    200-700 kPa".  This profile has the same character and, by default, the same
    130 s: the 13 segments of :data:`FIG8_SEGMENTS`, each of length `segment`,
    a step to or a linear ramp towards a pair of static pressures (kPa abs):

    ==  ====  ===  ===    ==  ====  ===  ===    ==  ====  ===  ===
    #   kind  P1   P2     #   kind  P1   P2     #   kind  P1   P2
    ==  ====  ===  ===    ==  ====  ===  ===    ==  ====  ===  ===
    1   step  300  450    6   ramp  200  700    11  ramp  550  650
    2   ramp  600  450    7   ramp  700  700    12  step  350  500
    3   step  400  700    8   step  700  400    13  ramp  200  250
    4   ramp  400  300    9   ramp  500  500
    5   step  200  600    10  step  300  300
    ==  ====  ===  ===    ==  ====  ===  ===    ==  ====  ===  ===

    Pressures become voltages through :func:`pressure_to_voltage` (the static
    pressure is linear in u by the design of :func:`kappa`).  The pairs keep every
    rest angle within -13..+18 deg and every locked torque within -1.6..+2.8 N m,
    inside the rig's +-25 deg and +-3 N m (Sec. II-A of [1]_).  P2 stays at or above
    250 kPa: muscle 1 is the stronger (Table II), and at P1 = P2 = 200 kPa the joint
    would rest at 25 deg.

    Parameters
    ----------
    segment : float, s
        Length of each segment (a whole number of 1 ms samples).
    params : mapping str -> float, optional
        For ``P_out`` and ``P_tank`` of the pressure-to-voltage map.

    Returns
    -------
    t : ndarray, shape (n,), s
        ``0, 1 ms, ..., 13 * segment``.
    u : ndarray, shape (n, 2), V
        ``(u1, u2)``; row ``k`` is held over ``[t_k, t_k + 1 ms)``.

    Examples
    --------
    >>> t, u = fig8_profile()
    >>> t.shape, u.shape, float(t[-1])
    ((130001,), (130001, 2), 130.0)
    """
    m = int(round(segment / SAMPLE_TIME))
    if m < 1 or abs(m * SAMPLE_TIME - segment) > 1e-9:
        raise ArgumentError(f"segment must be a positive whole number of {SAMPLE_TIME} s samples, got {segment!r}")
    n_seg = len(FIG8_SEGMENTS)
    P = np.empty((n_seg * m + 1, 2))
    prev = np.array(FIG8_SEGMENTS[0][1:])
    ramp = np.arange(m)[:, None] / m                  # 0 .. (m-1)/m within a segment
    for j, (kind, *target) in enumerate(FIG8_SEGMENTS):
        target = np.array(target)
        rows = slice(j * m, (j + 1) * m)
        P[rows] = target if kind == "step" else prev + (target - prev) * ramp
        prev = target
    P[-1] = prev
    return np.arange(n_seg * m + 1) * SAMPLE_TIME, pressure_to_voltage(P * 1e3, params)
