"""Antagonistic PAM joint (seed 000): the state-space model (11a) written in plain numpy.

References: seed 000 (``docs/references.md``) ([1]: eqs. (2)-(11), Table II, Sec. II-A) and
``docs/pam-conventions.md`` ([2]: kappa knots, orifice law, index readings, Kikuuwe friction,
fixed-step scheme).  Reference numbers below are computed in the tests from the textbook formulas
quoted in [2], not from the module.
"""
import math

import numpy as np
import pytest

from plants.blockdiagram import pam
from bondgraph.errors import ParameterError

P = pam.PARAMS
K, R, T_AIR = P["k"], P["R"], P["T"]
# [2], "Valve flows": critical ratio and per-unit-area choked / sub-critical laws
X_CRIT = (2 / (K + 1)) ** (K / (K - 1))                                        # 0.5283 for k = 1.4


def _choked(P_up):
    return P_up * math.sqrt(K / R) * (2 / (K + 1)) ** ((K + 1) / (2 * (K - 1))) / math.sqrt(T_AIR)


def _unchoked(P_up, x):
    return P_up * math.sqrt(2 * K / (R * (K - 1))) * x ** (1 / K) * math.sqrt(1 - x ** ((K - 1) / K)) / math.sqrt(T_AIR)


def _p_lin(u):
    """Static pressure the kappa knots were built for ([2]): linear from P_out (0 V) to P_tank (10 V)."""
    return P["P_out"] + (P["P_tank"] - P["P_out"]) * np.asarray(u) / 10.0


def _hold(u, T):
    return np.tile(np.asarray(u, dtype=float), (int(round(T / pam.SAMPLE_TIME)), 1))


# --- kappa and valve, eq. (5) ------------------------------------------------------------------

def test_kappa_at_knots_and_clipping():
    assert np.array_equal(pam.kappa(np.array(pam.KAPPA_U)), np.array(pam.KAPPA_ALPHA))   # [2] table
    assert pam.kappa(-3.0) == 0.0 and pam.kappa(12.0) == 1.0                           # u clipped to [0, 10]
    assert pam.kappa(9.75) == pytest.approx(0.5 * (0.6962 + 1.0))                      # linear between knots
    assert np.all(np.diff(pam.kappa(np.linspace(0, 10, 1001))) >= 0)                   # monotone ([1] Sec. II-B2)


def test_critical_ratio_and_flow_law_both_sides_of_it():
    assert X_CRIT == pytest.approx(0.528282, abs=1e-6)
    # the two textbook branches meet at the critical ratio (continuity, [2])
    assert _unchoked(P["P_tank"], X_CRIT) == pytest.approx(_choked(P["P_tank"]), rel=1e-12)
    # u = 10 V: alpha = 1, m = A1 m_in (filling); the module against the textbook law on both sides
    for x in (0.2, 0.4, X_CRIT * (1 - 1e-9), X_CRIT * (1 + 1e-9), 0.6, 0.8, 0.95, 0.999):
        ref = _choked(P["P_tank"]) if x <= X_CRIT else _unchoked(P["P_tank"], x)
        assert pam.valve_mass_flow(10.0, x * P["P_tank"]) == pytest.approx(P["A1"] * ref, rel=1e-12)
    # u = 0 V: alpha = 0, m = -A2 m_out (exhausting to P_out)
    for P_muscle in (150e3, P["P_out"] / X_CRIT, 300e3, 700e3):
        x = P["P_out"] / P_muscle
        ref = _choked(P_muscle) if x <= X_CRIT else _unchoked(P_muscle, x)
        assert pam.valve_mass_flow(0.0, P_muscle) == pytest.approx(-P["A2"] * ref, rel=1e-12)
    # no jump across the critical ratio (the printed exponents of eq. (5) would make one of ~20 %):
    # a relative step of 1e-9 in P moves m by O(1e-9) only, for the pure inflow and for a mixed valve
    Pc = X_CRIT * P["P_tank"]
    for u in (10.0, 6.0):
        m = pam.valve_mass_flow(u, np.array([Pc * (1 - 1e-9), Pc, Pc * (1 + 1e-9)]))
        assert np.ptp(m) < 1e-7 * abs(m[1])


def test_zero_flow_at_equal_pressures_and_reversal():
    assert pam.valve_mass_flow(10.0, P["P_tank"]) == 0.0       # alpha = 1, muscle at tank pressure
    assert pam.valve_mass_flow(0.0, P["P_out"]) == 0.0         # alpha = 0, muscle at atmosphere
    # pressures reversed: same law, opposite sign, no NaN ([2]); A0 = A2 for outflow, A1 for inflow
    above_tank = pam.valve_mass_flow(10.0, 800e3)
    assert above_tank == pytest.approx(-P["A2"] * _unchoked(800e3, P["P_tank"] / 800e3), rel=1e-12)
    below_atm = pam.valve_mass_flow(0.0, 90e3)
    assert below_atm == pytest.approx(P["A1"] * _unchoked(P["P_out"], 90e3 / P["P_out"]), rel=1e-12)
    m = pam.valve_mass_flow(np.linspace(0, 10, 41)[:, None], np.linspace(50e3, 900e3, 60)[None, :])
    assert np.all(np.isfinite(m))
    assert np.all(np.diff(m, axis=1) <= 0)                     # flow falls as the muscle pressure rises


# --- static pressure (Proposition 1 of [1], kappa design of [2]) -------------------------------

def test_static_pressure_linear_and_monotone_in_u():
    knots = np.array(pam.KAPPA_U)
    Ps = pam.static_pressure(knots)
    assert Ps[0] == pytest.approx(P["P_out"], abs=1.0) and Ps[-1] == pytest.approx(P["P_tank"], abs=1.0)
    assert np.max(np.abs(Ps - _p_lin(knots))) < 100.0          # Pa: the knots realise the linear design
    fine = np.linspace(0, 10, 401)
    Pf = pam.static_pressure(fine)
    assert np.all(np.diff(Pf) > 0)                             # strictly monotone in u
    assert np.max(np.abs(Pf - _p_lin(fine))) < 12e3            # between knots (worst near 9.7 V, ~10 kPa)
    # no dependence on the orifice areas (proof of Proposition 1)
    assert np.allclose(pam.static_pressure(knots, {"A1": 1e-7, "A2": 2e-8}), Ps, rtol=0, atol=1e-3)


@pytest.mark.parametrize("u1", [0.0, 1.0, 2.0, 3.0, 4.0, 5.0])
def test_locked_variant_rests_on_the_linear_static_pressure(u1):
    u = (u1, 10.0 - u1)
    x0 = [0.0, 0.0, *_p_lin(u)]
    r = pam.simulate(_hold(u, 1.0), 1.0, variant="locked", x0=x0)
    assert np.max(np.abs(r["P1"] - x0[2])) < 300.0 and np.max(np.abs(r["P2"] - x0[3])) < 300.0


def test_locked_variant_converges_to_static_pressure_from_vented():
    u = (2.0, 8.0)
    r = pam.simulate(_hold(u, 20.0), 20.0, variant="locked")    # x0: vented muscles
    Ps = pam.static_pressure(np.array(u))
    assert abs(r["P1"][-1] - Ps[0]) < 1.5e3 and abs(r["P2"][-1] - Ps[1]) < 1.5e3
    assert np.all(np.diff(r["P1"]) >= 0) and np.all(np.diff(r["P2"]) >= 0)   # filling only, no overshoot
    assert np.all(r["psi_deg"] == 0.0)


# --- eqs. (2)-(4), (6)-(7), (9) ----------------------------------------------------------------

def test_geometry_volume_rate_and_forces():
    psi, dpsi = 0.2, 1.5
    l1, l2, l1d, l2d = pam.muscle_lengths(psi, dpsi)
    assert (l1, l2) == pytest.approx((P["L0"] - P["r"] * math.sin(psi), P["L0"] + P["r"] * math.sin(psi)))
    eps = 1e-6                                                 # V_dot against a central difference of V(l(psi))
    fd = (pam.volume(pam.muscle_lengths(psi + eps * dpsi, 0)[0]) - pam.volume(pam.muscle_lengths(psi - eps * dpsi, 0)[0])) / (2 * eps)
    assert pam.volume_rate(l1, l1d) == pytest.approx(fd, rel=1e-7)
    # eq. (3) at L0 by hand: -6.6429e-4 + 1.12596e-3 - 4.254e-4 = 3.6270e-5 m^3 (36 cm^3)
    assert pam.volume(P["L0"]) == pytest.approx(3.6270e-5, rel=1e-9)
    # eqs. (6)-(7), last index = muscle ([2]): at L0 and 400 kPa, by hand
    assert pam.contraction_force(400e3, 0.165, 1) == pytest.approx((7.045e-3 * 0.165 - 1.017e-3) * 400e3 - 556.8 * 0.165 + 72.86)
    assert pam.contraction_force(400e3, 0.165, 2) == pytest.approx((6.423e-3 * 0.165 - 9.184e-4) * 400e3 - 197.8 * 0.165 - 15.75)
    x = np.array([psi, dpsi, 400e3, 500e3])
    F1, F2 = pam.contraction_force(400e3, l1, 1), pam.contraction_force(500e3, l2, 2)
    assert pam.joint_torque(x) == pytest.approx(P["r"] * math.cos(psi) * (F1 - F2))      # eq. (9)
    # eq. (4) with no flow: isentropic-like compression P_dot = -k2 (V_dot/V) P
    assert pam.chamber_rates(400e3, 0.0, 3e-5, -1e-6) == pytest.approx(P["k2"] * 400e3 / 30)
    with pytest.raises(ValueError, match="muscle must be 1 or 2"):
        pam.contraction_force(400e3, 0.165, 3)


def test_derivatives_batch_matches_rows(rng):
    X = np.column_stack([rng.uniform(-0.3, 0.3, 7), rng.uniform(-2, 2, 7),
                         rng.uniform(150e3, 700e3, 7), rng.uniform(150e3, 700e3, 7)])
    U = rng.uniform(0, 10, (7, 2))
    Tf = rng.uniform(-0.1, 0.1, 7)
    batch = pam.derivatives(X, U, None, Tf)
    rows = np.array([pam.derivatives(x, u, None, t) for x, u, t in zip(X, U, Tf)])
    assert batch.shape == (7, 4) and np.allclose(batch, rows, rtol=1e-12, atol=0)
    assert np.array_equal(batch[:, 0], X[:, 1])
    tau = pam.joint_torque(X)
    assert np.allclose(batch[:, 1], (tau - P["k_s"] * X[:, 0] - Tf) / P["J"], rtol=1e-13)   # eq. (8)


# --- friction, eq. (10) ------------------------------------------------------------------------

def _coulomb_level(x):
    """T_s + T_p of [1] (eq. (10)), with the 20 kPa clamp of [2]."""
    l1, l2, _, _ = pam.muscle_lengths(x[0], 0.0)
    F1, F2 = pam.contraction_force(x[2], l1, 1), pam.contraction_force(x[3], l2, 2)
    T_s = P["r_p"] * P["mu_s"] * abs(F1 + F2 - P["M"] * P["g"])
    T_p = P["mu_p"] * sum(1 / max(Pi - P["P_out"], 20e3) ** 2 for Pi in x[2:])
    return T_s + T_p


def test_kikuuwe_branches_and_continuity():
    h = 0.25e-3
    Z = h / P["J"]
    x = np.array([0.1, 0.0, 400e3, 450e3])
    T0 = pam.joint_torque(x) - P["k_s"] * x[0]
    Fc = _coulomb_level(x)
    # stick: T_f cancels T0 and the current velocity (w / Z = T0 + J dpsi / h)
    for v in (0.0, 0.1 * Z * Fc, -0.3 * Z * Fc):
        xs = x.copy()
        xs[1] = v - Z * T0                                    # chosen so that w = v
        assert pam.kikuuwe_friction(xs, None, h) == pytest.approx(v / Z, rel=1e-9, abs=1e-15)
    # slip: (Fc sgn(w) + c_s w) / (1 + Z c_s)
    xs = x.copy()
    xs[1] = 3.0
    w = 3.0 + Z * T0
    assert pam.kikuuwe_friction(xs, None, h) == pytest.approx((Fc + P["c_s"] * w) / (1 + Z * P["c_s"]), rel=1e-12)
    # the branches meet at |w| = Z Fc
    edge = x.copy()
    edge[1] = Z * Fc - Z * T0
    assert pam.kikuuwe_friction(edge, None, h) == pytest.approx(Fc, rel=1e-9)
    # T_p clamp: at atmospheric pressure T_p = 2 mu_p / (20 kPa)^2 = 2 N m, finite
    vented = np.array([0.0, 0.0, P["P_out"], P["P_out"]])
    assert np.isfinite(pam.kikuuwe_friction(vented))


def _rest_angle_with_torque(u, target):
    """Angle where T0 = tau - k_s psi equals `target`, at the static pressures of u (bisection)."""
    x = pam.equilibrium(u)
    lo, hi = x[0] - 0.3, x[0] + 0.3                            # T0 decreases in psi (restoring)
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        T0 = pam.joint_torque([mid, 0, x[2], x[3]]) - P["k_s"] * mid
        lo, hi = (mid, hi) if T0 > target else (lo, mid)
    x[0] = 0.5 * (lo + hi)
    return x


def test_friction_holds_the_joint_while_T0_below_coulomb_level():
    u = (5.0, 5.0)
    x_eq = pam.equilibrium(u)
    Fc = _coulomb_level(x_eq)
    assert 0.05 < Fc < 0.2                                    # N m at 406 kPa: T_s ~ 0.06, T_p ~ 0.009
    x0 = _rest_angle_with_torque(u, -0.6 * Fc)                # |T0| = 0.6 (T_s + T_p): must stick
    held = pam.simulate(_hold(u, 0.5), 0.5, x0=x0)
    T0 = held["tau"] - P["k_s"] * held["x"][:, 0]
    assert np.all(np.abs(T0) < np.array([_coulomb_level(x) for x in held["x"][::50]]).min())
    assert np.max(np.abs(held["x"][:, 0] - x0[0])) < 1e-7     # rad: still
    free = pam.simulate(_hold(u, 0.5), 0.5, x0=x0, variant="frictionless")
    assert np.max(np.abs(free["x"][:, 0] - x0[0])) > 0.5 * abs(x0[0] - x_eq[0])
    x1 = _rest_angle_with_torque(u, -2.0 * Fc)                # |T0| = 2 (T_s + T_p): must slip
    slip = pam.simulate(_hold(u, 0.5), 0.5, x0=x1)
    moved = abs(slip["x"][-1, 0] - x1[0])
    assert moved > 0.5 * abs(x1[0] - x0[0])
    T0_end = slip["tau"][-1] - P["k_s"] * slip["x"][-1, 0]
    assert abs(T0_end) <= _coulomb_level(slip["x"][-1]) and abs(slip["x"][-1, 1]) < 1e-6   # stuck again


# --- integration scheme ------------------------------------------------------------------------

def test_rk4_scheme_matches_solve_ivp_frictionless():
    from scipy.integrate import solve_ivp

    u = pam.pressure_to_voltage(np.array([500e3, 350e3]))     # away from x0's pressures: all states move
    x0 = np.array([0.0, 0.0, 300e3, 450e3])
    T = 0.2
    r = pam.simulate(_hold(u, T), T, variant="frictionless", x0=x0)
    ref = solve_ivp(lambda t, x: pam.derivatives(x, u), (0.0, T), x0, method="DOP853", t_eval=r["t"],
                    rtol=1e-12, atol=[1e-12, 1e-10, 1e-6, 1e-6])
    assert ref.success
    assert np.ptp(r["psi_deg"]) > 5.0                          # a real swing, not a trivial run
    assert np.max(np.abs(r["x"][:, 0] - ref.y[0])) < 1e-7     # rad; RK4 with h = 0.25 ms, omega ~ 120 rad/s
    assert np.max(np.abs(r["x"][:, 1] - ref.y[1])) < 2e-5     # rad/s
    assert np.max(np.abs(r["x"][:, 2:] - ref.y[2:].T)) < 0.02  # Pa, i.e. < 1e-7 relative


def test_inputs_are_held_per_sample():
    x0 = np.array([0.0, 0.0, 300e3, 300e3])
    u = np.array([[10.0, 0.0], [0.0, 10.0], [5.0, 5.0]])
    a = pam.simulate(u, 0.002, variant="locked", x0=x0)
    b = pam.simulate(u[:1], 0.001, variant="locked", x0=x0)
    assert np.array_equal(a["x"][:2], b["x"])                 # sample 0 sees only u[0]
    assert a["P1"][1] > 300e3 and a["P1"][2] < a["P1"][1]     # filling, then exhausting
    assert a["t"].tolist() == [0.0, 0.001, 0.002]


# --- the Fig. 8-like profile (Sec. II-A of [1]: +-25 deg, +-3 N m) ------------------------------

def test_fig8_profile_shape_and_pressure_range():
    t, u = pam.fig8_profile()
    assert t[-1] == pytest.approx(130.0) and u.shape == (130001, 2)   # N = 130e3 samples as in [1]
    Pstat = _p_lin(u)
    assert Pstat.min() == pytest.approx(200e3) and Pstat.max() == pytest.approx(700e3)
    for kind, P1, P2 in pam.FIG8_SEGMENTS:                    # every rest state within the rig's ranges
        ui = pam.pressure_to_voltage(np.array([P1, P2]) * 1e3)
        assert abs(np.degrees(pam.equilibrium(ui)[0])) < 25.0
        assert abs(pam.joint_torque(pam.equilibrium(ui, variant="locked"))) < 3.0


@pytest.fixture(scope="module")
def fig8_runs():
    t, u = pam.fig8_profile(segment=3.0)                      # 39 s: the 130 s profile, time-compressed
    return {v: pam.simulate(u, t[-1], variant=v, x0=pam.equilibrium(u[0], variant=v))
            for v in ("full", "locked")}


def test_fig8_free_joint_angle_within_25_deg(fig8_runs):
    r = fig8_runs["full"]
    assert np.max(np.abs(r["psi_deg"])) < 25.0
    assert r["psi_deg"].min() < -5.0 and r["psi_deg"].max() > 10.0    # both directions exercised
    assert r["P1"].min() < 260e3 and r["P1"].max() > 600e3


def test_fig8_locked_torque_within_3_Nm(fig8_runs):
    r = fig8_runs["locked"]
    assert np.all(r["psi_deg"] == 0.0)
    assert np.max(np.abs(r["tau"])) < 3.0
    assert r["tau"].min() < -1.0 and r["tau"].max() > 2.0


# --- boundaries --------------------------------------------------------------------------------

def test_bad_arguments_are_rejected_with_names():
    u = _hold((5.0, 5.0), 0.01)
    with pytest.raises(ParameterError, match="unknown parameter.*J_typo") as exc:
        pam.simulate(u, 0.01, params={"J_typo": 1.0})
    assert exc.value.name == "J_typo"
    with pytest.raises(ValueError, match="expected one of full, frictionless, locked"):
        pam.simulate(u, 0.01, variant="free")
    with pytest.raises(ValueError, match="locked variant holds psi"):
        pam.simulate(u, 0.01, variant="locked", x0=[0.1, 0.0, 3e5, 3e5])
    with pytest.raises(ValueError, match="n_samples >= 20"):
        pam.simulate(u, 0.02)
    with pytest.raises(ValueError, match="whole number"):
        pam.simulate(u, 0.0105)


def test_params_override_changes_the_plant():
    x = np.array([0.0, 0.0, 400e3, 400e3])
    assert pam.joint_torque(x, {"r": 2 * P["r"]}) == pytest.approx(2 * pam.joint_torque(x))
    assert pam.PARAMS["r"] == 0.0365                          # overrides never touch PARAMS
