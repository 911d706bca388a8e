"""Truth plants of the antagonistic PAM joint (seed 000), hand-written in physical states.

Shin, Ibayashi, Kogiso, "Detailed dynamic model of antagonistic PAM system
and its experimental validation: sensor-less angle and torque control with
UKF" -- eqs. (2)-(11), Table II -- read as the project's PAM conventions
prescribe (plants/models.md, "Antagonistic PAM joint").  State
``x = (psi [rad], dpsi [rad/s], P1 [Pa abs], P2 [Pa abs])``; inputs ``u1``,
``u2`` (V, clipped to [0, 10]); outputs ``psi`` (deg), ``P1``, ``P2`` (Pa,
absolute) and ``tau`` (N m), eq. (11b).

Effect doors (names are the nominal graph's element names):

* ``extra["seesaw"]`` (N m): a torque into the seesaw 1-junction (velocity
  ``dpsi``); it enters eq. (8) and, in :func:`pam`, the Kikuuwe predicted
  velocity too (so a stuck joint feels it).
* ``extra["chamber1"]``, ``extra["chamber2"]`` (kg/s): a mass flow into
  chamber i, the nominal graph's 0-junction ``chamber<i>`` between the valve
  and the muscle (common effort: the pressure, ambient ``P_out``): a leak
  (``-Q(P - P_out)``) or a constant flow.  ``laws["chamber"](x)`` gives, per
  chamber, its pressure, volume and the ambient pressure.
* ``extra["muscle1"]``, ``extra["muscle2"]`` (N): a force added to muscle i's force law
  eqs. (6)-(7), in the sense of its contraction force (the nominal graph's law place
  ``law muscle<i>``: the bond from the lever arm to the muscle); ``signals`` gives its
  contraction rate (m/s), so that an added ``-z`` opposing it is a friction, as at a junction.  The ``tau`` output stays eq. (11b) of the pressures and the angle,
  as the library's output is: it does not see a change of the force law.
* storage ``k_s`` (C of the seesaw, content ``psi``).

Signals: ``seesaw`` (dpsi, rad/s), ``P1``, ``P2`` (Pa, for pressure-dependent
friction), ``chamber1``/``chamber2`` (the chamber pressures), ``k_s`` (psi, rad).
"""
from __future__ import annotations

import math

import numpy as np

from .plant import InputSpec, JunctionSpec, OutputSpec, StorageSpec, TruthPlant

__all__ = ["pam", "pam_frictionless", "PAM_PARAMS"]

#: Table II (SI); the last index of p_v/p_w is the muscle (conventions).
PAM_PARAMS = dict(
    r_p=0.006, r=0.0365, L0=0.165, M=0.256, g=9.80,       # m, m, m, kg, m/s^2
    P_tank=0.7100e6, P_out=0.1013e6,                       # Pa absolute
    k=1.40, R=287.0, T=293.0,                              # -, J/(kg K), K
    J=4.263e-4, k_s=4.117e-4, c_s=2.256e-3,                # kg m^2, N m/rad, N m s/rad
    k1=1.100, k2=0.4545,                                   # polytropic indices, eq. (4)
    D1=-2.440e-2, D2=6.824e-3, D3=-4.254e-4,               # m, m^2, m^3, eq. (3)
    A1=5.184e-8, A2=7.776e-8,                              # m^2, filling / exhaust orifice
    mu_p=4e8, mu_s=0.2,                                    # N m Pa^2, -
)
#: (p_v1, p_v2, p_w1, p_w2) of eq. (7) per muscle: m, m^2, N/m, N.
_FORCE = {1: (7.045e-3, -1.017e-3, -556.8, 72.86), 2: (6.423e-3, -9.184e-4, -197.8, -15.75)}
#: kappa(u) knots (conventions): u in V -> open rate alpha.
_KU = [0.5 * j for j in range(21)]
_KA = [0.0, 0.1378, 0.1828, 0.2134, 0.2390, 0.2631, 0.2856, 0.3069, 0.3269, 0.3458, 0.3645,
       0.3844, 0.4057, 0.4288, 0.4545, 0.4835, 0.5174, 0.5589, 0.6134, 0.6962, 1.0]
_DP_CLAMP = 20e3          # Pa, lower clamp of P_i - P_out in T_p (conventions)
_MUSCLES = ("muscle1", "muscle2")   # the force-law doors (the graph's PneumaticChamber elements)
_SUBSTEPS = 4             # RK4 sub-steps per 1 ms sample: h = 0.25 ms, the friction hold


class _Pam:
    """The equations of the joint on Python floats (eqs. (2)-(10))."""

    def __init__(self, p=PAM_PARAMS):
        self.p = p
        k, R, T = p["k"], p["R"], p["T"]
        self.x_crit = (2.0 / (k + 1.0)) ** (k / (k - 1.0))          # critical pressure ratio ~0.528
        self.phi = math.sqrt(2.0 * k / (R * (k - 1.0)) / T)           # sub-critical coefficient
        self.k1RT = p["k1"] * R * T

    @staticmethod
    def alpha(u):
        """kappa(u): valve open rate, piecewise linear through the knots, u clipped to [0, 10] V."""
        u = min(max(u, 0.0), 10.0)
        j = min(int(u / 0.5), 19)
        return _KA[j] + (_KA[j + 1] - _KA[j]) * (u - _KU[j]) / 0.5

    def flux(self, pa, pb):
        """Signed compressible-orifice mass flux a -> b per unit area, kg/(s m^2) (eq. (5), corrected)."""
        up, down = max(pa, pb), min(pa, pb)
        x = max(down / up, self.x_crit)           # choked below the critical ratio
        s = float(pa > pb) - float(pa < pb)
        return s * up * self.phi * x ** (1.0 / self.p["k"]) * math.sqrt(max(1.0 - x ** ((self.p["k"] - 1.0) / self.p["k"]), 0.0))

    def mass_flow(self, u, P):
        """Valve mass flow into the muscle, kg/s: A0 (alpha m_in - (1 - alpha) m_out), eq. (5)."""
        a = self.alpha(u)
        m = a * self.flux(self.p["P_tank"], P) - (1.0 - a) * self.flux(P, self.p["P_out"])
        return (self.p["A1"] if m > 0.0 else self.p["A2"]) * m

    def volume(self, l):
        return (self.p["D1"] * l + self.p["D2"]) * l + self.p["D3"]        # eq. (3), m^3

    def force(self, i, P, l):
        pv1, pv2, pw1, pw2 = _FORCE[i]
        return (pv1 * l + pv2) * P + pw1 * l + pw2                          # eqs. (6)-(7), N

    def mechanics(self, psi, P1, P2, extra=None):
        """Lengths (eq. (2)), forces and the joint torque eq. (9); `extra` may add a force to a
        muscle's law (``extra["muscle<i>"]``, N, in the sense of its contraction force)."""
        s = self.p["r"] * math.sin(psi)
        l1, l2 = self.p["L0"] - s, self.p["L0"] + s
        F1, F2 = self.force(1, P1, l1), self.force(2, P2, l2)
        if extra:
            F1, F2 = F1 + extra.get("muscle1", 0.0), F2 + extra.get("muscle2", 0.0)
        return l1, l2, F1, F2, self.p["r"] * math.cos(psi) * (F1 - F2)

    def chamber(self, P, m, l, l_dot):
        """Eq. (4): dP/dt = k1 R T m / V - k2 (dV/dt / V) P, dV/dt = (2 D1 l + D2) dl/dt."""
        V = self.volume(l)
        return (self.k1RT * m - self.p["k2"] * (2.0 * self.p["D1"] * l + self.p["D2"]) * l_dot * P) / V

    def kikuuwe(self, x, extra, h):
        """Friction torque eq. (10) (conventions: Z = h/J, T_p clamp), N m, held over a sub-step."""
        p = self.p
        psi, dpsi, P1, P2 = (float(v) for v in x)
        if not math.isfinite(psi):
            return math.nan
        _, _, F1, F2, tau = self.mechanics(psi, P1, P2, extra)
        Z = h / p["J"]
        T0 = tau - p["k_s"] * psi + extra.get("seesaw", 0.0)   # every torque but friction
        w = dpsi + Z * T0                                     # implicit-Euler velocity without friction
        T_s = p["r_p"] * p["mu_s"] * abs(F1 + F2 - p["M"] * p["g"])
        d1, d2 = max(P1 - p["P_out"], _DP_CLAMP), max(P2 - p["P_out"], _DP_CLAMP)
        Fc = T_s + p["mu_p"] * (1.0 / (d1 * d1) + 1.0 / (d2 * d2))
        if abs(w) > Z * Fc:
            return (Fc * math.copysign(1.0, w) + p["c_s"] * w) / (1.0 + Z * p["c_s"])
        return w / Z

    def rhs(self, x, u, extra):
        p = self.p
        psi, dpsi, P1, P2 = (float(v) for v in x)
        if not math.isfinite(psi):          # a run an effect has driven out of range: NaN, no raise
            return np.full(4, np.nan)
        l1, l2, _, _, tau = self.mechanics(psi, P1, P2, extra)
        ld = p["r"] * math.cos(psi) * dpsi                   # dl2/dt = -dl1/dt
        m1 = self.mass_flow(u["u1"], P1) + extra.get("chamber1", 0.0)
        m2 = self.mass_flow(u["u2"], P2) + extra.get("chamber2", 0.0)
        ddpsi = (tau - p["k_s"] * psi - u.get("T_f", 0.0) + extra.get("seesaw", 0.0)) / p["J"]   # eq. (8)
        return np.array([dpsi, ddpsi, self.chamber(P1, m1, l1, -ld), self.chamber(P2, m2, l2, ld)])

    def static_pressure(self, u):
        """Pressure where the valve flow vanishes (bisection; the flow falls monotonically in P)."""
        lo, hi = self.p["P_out"], self.p["P_tank"]
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if self.mass_flow(u, mid) > 0.0 else (lo, mid)
        return 0.5 * (lo + hi)

    def rest(self, u1, u2):
        """Rest state at constant inputs: static pressures, angle where tau = k_s psi (|psi| < 0.6 rad)."""
        P1, P2 = self.static_pressure(u1), self.static_pressure(u2)

        def T0(psi):
            return self.mechanics(psi, P1, P2)[-1] - self.p["k_s"] * psi

        lo, hi = -0.6, 0.6
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if T0(mid) * T0(lo) > 0.0 else (lo, mid)
        return np.array([0.5 * (lo + hi), 0.0, P1, P2])


def _build(name: str, model: str, friction: bool) -> TruthPlant:
    j = _Pam()
    p = j.p

    def signals(x, u):
        # a law door's flow is its muscle's contraction rate (dl2/dt = -dl1/dt = r cos(psi) dpsi):
        # with the force added to its contraction force, extra * flow is the power into the muscle
        # side, as at a junction (a friction -z opposing it is dissipative)
        ld = p["r"] * math.cos(x[0]) * x[1] if math.isfinite(x[0]) else math.nan   # a run gone to inf
        return {"seesaw": x[1], "P1": x[2], "P2": x[3], "chamber1": x[2], "chamber2": x[3], "k_s": x[0],
                "muscle1": ld, "muscle2": -ld}

    def measure(x, u):
        return {"psi": math.degrees(x[0]), "P1": x[2], "P2": x[3], "tau": j.mechanics(x[0], x[2], x[3])[-1]}

    def chamber(x):
        s = p["r"] * math.sin(x[0])
        return {"chamber1": {"P": x[2], "V": j.volume(p["L0"] - s), "ambient": p["P_out"]},
                "chamber2": {"P": x[3], "V": j.volume(p["L0"] + s), "ambient": p["P_out"]}}

    def hold(x, u, extra, h):
        return {"T_f": j.kikuuwe(x, extra, h)}

    x0 = j.rest(5.0, 5.0)
    valve = dict(unit="V", low=0.5, high=9.5, quantum=0.01, hold=(0.2, 0.8), ambient=5.0)
    return TruthPlant(
        name=name, model=model,
        # the cases drive the valves antagonistically (u1 = 5 + a, u2 = 5 - a); independent levels
        # in the same range are what this spec draws: co-contraction as well as antagonism
        inputs=(InputSpec("u1", **valve), InputSpec("u2", **valve)),
        outputs=(OutputSpec("psi", "deg"), OutputSpec("P1", "Pa"), OutputSpec("P2", "Pa"),
                 OutputSpec("tau", "N m")),
        states=("psi", "dpsi", "P1", "P2"),
        # the recording starts at rest at the valves' ambient 5 V (406 kPa each, psi = +10.4 deg):
        # the library's default (vented muscles, psi = 0) is not a rest state of the frictionless
        # joint (from there it swings past the muscles' range on a valve step and the run fails)
        x0=x0, nominal_x0={"q_psi": x0[0], "p_J": p["J"] * x0[1], "P_1": x0[2], "P_2": x0[3]},
        rhs=j.rhs, signals=signals, measure=measure,
        junctions=(JunctionSpec("seesaw", "1", "rotation", pressures=("P1", "P2"), equivalent=_MUSCLES),
                   JunctionSpec("chamber1", "0", "pneumatic", ambient=p["P_out"]),
                   JunctionSpec("chamber2", "0", "pneumatic", ambient=p["P_out"]),
                   # each muscle's force law (eqs. (6)-(7)) acts on the seesaw only through its
                   # lever arm r cos(psi): the same place as the seesaw up to that modulus
                   # (and the two muscles' through arms of opposite sign: dl2 = -dl1, F1 - F2)
                   *(JunctionSpec(m, "1", "translation", law=True,
                                  equivalent=("seesaw",) + tuple(o for o in _MUSCLES if o != m))
                     for m in _MUSCLES)),
        storages=(StorageSpec("k_s", "seesaw", p["k_s"], content_range=(-0.6, 0.6)),),
        rate=1000.0, duration=15.0, substeps=_SUBSTEPS, method="rk4",
        drifts=False, laws={"chamber": chamber}, hold=hold if friction else None,
        description="antagonistic PAM joint, seed 000" + ("" if friction else " without joint friction"))


def pam() -> TruthPlant:
    """The seed-000 joint with Kikuuwe friction eq. (10), held per 0.25 ms RK4 sub-step (library ``pam``)."""
    return _build("pam", "pam", friction=True)


def pam_frictionless() -> TruthPlant:
    """The seed-000 joint with T_f = 0 (library ``pam-frictionless``).

    Not a drifting model: the muscles' length-dependent forces (eq. (7)) and
    the chambers' volume-dependent pressures (eq. (4)) pull psi back to the
    angle where tau = k_s psi, so psi stays bounded on random valve commands
    (checked in tests/test_benchmark_plants.py); only its damping is small.
    """
    return _build("pam-frictionless", "pam-frictionless", friction=False)
