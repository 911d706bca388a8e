"""Antagonistic PAM joint (seed 000) as a bond graph: physics tests and analytic spot checks.

References: seed 000 (``docs/references.md``) ([1]: eqs. (2)-(11), Table II, Sec. II-A)
and ``docs/pam-conventions.md`` ([C]: kappa table, orifice law, friction, fixed-step scheme).
Every hand formula below is written here from those texts, independently of
``plants/library/pam.py``.
"""
import math

import numpy as np
import pytest

from bondgraph import ParameterError
from bondgraph.numerics import compile_model, simulate
from plants.library.pam import FRICTION_STEP, KAPPA_KNOTS, PARAMETERS, pam

# Table II of [1], typed from the paper (last index of p_v/p_w = muscle, A_11 = A1, A_12 = A2,
# T'_p = mu_p per [C])
TABLE_II = {
    "r_p": 0.006, "r": 0.0365, "L0": 0.165, "M": 0.256, "g": 9.80, "P_tank": 0.7100e6,
    "P_out": 0.1013e6, "k": 1.40, "R": 287.0, "T": 293.0, "J": 4.263e-4, "k_s": 4.117e-4,
    "c_s": 2.256e-3, "k1": 1.100, "k2": 0.4545, "D1": -2.440e-2, "D2": 6.824e-3, "D3": -4.254e-4,
    "p_v11": 7.045e-3, "p_v21": -1.017e-3, "p_w11": -5.568e2, "p_w21": 72.86,
    "p_v12": 6.423e-3, "p_v22": -9.184e-4, "p_w12": -197.8, "p_w22": -15.75,
    "A1": 5.184e-8, "A2": 7.776e-8, "mu_p": 4e8, "mu_s": 0.2,
}
P = TABLE_II
# the kappa table of [C]
KAPPA = [0.0, 0.1378, 0.1828, 0.2134, 0.2390, 0.2631, 0.2856, 0.3069, 0.3269, 0.3458, 0.3645,
         0.3844, 0.4057, 0.4288, 0.4545, 0.4835, 0.5174, 0.5589, 0.6134, 0.6962, 1.0]
H = 0.25e-3    # [C]: 4 RK4 sub-steps per 1 ms sample


# -- hand formulas ------------------------------------------------------------------------

def length(i, psi):
    """[C] / eq. (2): l1 = L0 - r sin psi, l2 = L0 + r sin psi."""
    return P["L0"] + (-1 if i == 1 else 1) * P["r"] * np.sin(psi)


def volume(l):
    """Eq. (3)."""
    return P["D1"] * l ** 2 + P["D2"] * l + P["D3"]


def force(i, pressure, psi):
    """Eqs. (6)-(7), Table II with the last index the muscle ([C])."""
    l = length(i, psi)
    return ((P[f"p_v1{i}"] * l + P[f"p_v2{i}"]) * pressure + P[f"p_w1{i}"] * l + P[f"p_w2{i}"])


def torque(p1, p2, psi):
    """Eq. (9)."""
    return P["r"] * np.cos(psi) * (force(1, p1, psi) - force(2, p2, psi))


def flux(p_up, p_down):
    """Compressible-orifice mass flux per unit area, p_up >= p_down ([C], valve flows)."""
    k, R, T = P["k"], P["R"], P["T"]
    x = p_down / p_up
    if x <= (2 / (k + 1)) ** (k / (k - 1)):
        return p_up * math.sqrt(k / R) * (2 / (k + 1)) ** ((k + 1) / (2 * (k - 1))) / math.sqrt(T)
    return (p_up * math.sqrt(2 * k / (R * (k - 1))) * x ** (1 / k)
            * math.sqrt(1 - x ** ((k - 1) / k)) / math.sqrt(T))


def friction_torque(tau, psi, psi_dot, p1, p2, h=H):
    """Kikuuwe eq. (10) with [C]'s reading (Z = h/J, the 20 kPa clamp in T_p)."""
    Z = h / P["J"]
    T0 = tau - P["k_s"] * psi
    w = psi_dot + Z * T0
    Ts = P["r_p"] * P["mu_s"] * abs(force(1, p1, psi) + force(2, p2, psi) - P["M"] * P["g"])
    Tp = P["mu_p"] * sum(1 / max(p - P["P_out"], 20e3) ** 2 for p in (p1, p2))
    Fc = Ts + Tp
    if abs(w) > Z * Fc:
        return (Fc * np.sign(w) + P["c_s"] * w) / (1 + Z * P["c_s"]), Fc
    return w / Z, Fc


def static_pressure(u):
    """[C]: kappa is built so that the static pressure is linear in u."""
    return P["P_out"] + (P["P_tank"] - P["P_out"]) * u / 10


def fig8_inputs():
    """A Fig. 8-like profile of [1]: steps and ramps, co-contraction up to ~700 kPa, both
    muscles down to ~200 kPa, antagonistic ramps (u in V, piecewise linear)."""
    t = [0, 3, 3.001, 6, 9, 12, 12.001, 15, 18, 21, 24]
    u1 = [1.7, 1.7, 5.0, 5.0, 9.8, 9.8, 6.0, 6.0, 2.0, 2.0, 9.8]
    u2 = [1.7, 1.7, 5.0, 5.0, 5.0, 5.0, 9.8, 9.8, 9.8, 9.8, 9.8]
    return {"u1": lambda s: np.interp(s, t, u1), "u2": lambda s: np.interp(s, t, u2)}


@pytest.fixture(scope="module")
def models():
    return {v: compile_model(pam(v).equations()) for v in ("full", "frictionless", "locked")}


# -- structure ------------------------------------------------------------------------------

def test_parameters_are_table_ii_with_units_and_descriptions():
    assert {n: p.value for n, p in PARAMETERS.items()} == TABLE_II
    assert all(p.unit and p.description for p in PARAMETERS.values())
    assert [a for _, a in KAPPA_KNOTS] == KAPPA and [u for u, _ in KAPPA_KNOTS] == [0.5 * j for j in range(21)]


@pytest.mark.parametrize("variant, name, states, smooth", [
    ("full", "pam", ("P_1", "P_2", "p_J", "q_psi"), False),
    ("frictionless", "pam_frictionless", ("P_1", "P_2", "p_J", "q_psi"), True),
    ("locked", "pam_locked", ("P_1", "P_2"), True),
])
def test_variants_names_signals_and_regime(variant, name, states, smooth):
    g = pam(variant)
    eqs = g.equations()
    assert g.name == eqs.name == name
    assert eqs.state_names == states
    assert eqs.input_names == ("u1", "u2")
    assert tuple(eqs.outputs) == ("psi", "P1", "P2", "tau")
    assert [eqs.units[o] for o in eqs.outputs] == ["deg", "Pa", "Pa", "N m"]
    assert eqs.is_smooth is smooth
    assert eqs.held_names == (() if smooth else ("T_f",))
    if not smooth:
        assert eqs.fixed_step == FRICTION_STEP == H
    # initial state: psi = psi' = 0, both muscles at P_out (the valves' equilibrium at u = 0)
    assert eqs.initial_state == {**{s: 0.0 for s in states}, "P_1": P["P_out"], "P_2": P["P_out"]}
    assert not eqs.report.derivative_storage and not eqs.report.algebraic_loops


def test_bad_variant_and_parameter_are_named():
    with pytest.raises(ValueError, match="'full', 'frictionless', 'locked'.*'rigid'"):
        pam("rigid")
    with pytest.raises(ParameterError, match="no parameter.*Jx"):
        pam(params={"Jx": 1.0})
    assert pam(params={"J": 1e-3}).equations().param_values["J"] == 1e-3


# -- analytic spot checks on the compiled equations ------------------------------------------

def _dP1(model, p1, u1, psi=0.0, psi_dot=0.0):
    """dP_1/dt of `model` at P_1 = p1, P_2 = P_out, u = (u1, 0)."""
    x = {"P_1": p1, "P_2": P["P_out"], "q_psi": psi, "p_J": P["J"] * psi_dot}
    xv = np.array([x[s] for s in model.state_names], dtype=float)
    return model.f(xv, np.array([u1, 0.0]))[model.state_index["P_1"]]


def test_kappa_at_the_table_knots_and_clipping(models):
    # at P = P_out, m_out = 0 and m_in is choked (P_out/P_tank < 0.528): by eqs. (4)-(5)
    # dP/dt = k1 R T A1 alpha flux(P_tank, P_out) / V(L0), so alpha follows from dP/dt
    model = models["locked"]
    scale = P["k1"] * P["R"] * P["T"] * P["A1"] * flux(P["P_tank"], P["P_out"]) / volume(P["L0"])
    for u, alpha in zip([0.5 * j for j in range(21)], KAPPA):
        assert _dP1(model, P["P_out"], u) / scale == pytest.approx(alpha, rel=1e-12, abs=1e-15)
    assert _dP1(model, P["P_out"], 0.25) / scale == pytest.approx(KAPPA[1] / 2, rel=1e-12)
    assert _dP1(model, P["P_out"], -3.0) == 0.0                         # clipped to 0 V
    assert _dP1(model, P["P_out"], 12.0) / scale == pytest.approx(1.0, rel=1e-12)   # to 10 V


def test_orifice_flow_choked_unchoked_continuity_and_area_switch(models):
    model = models["locked"]
    k = P["k"]
    b = (2 / (k + 1)) ** (k / (k - 1))
    assert b == pytest.approx(0.5283, abs=1e-4)                          # [C]: ~0.528
    c = P["k1"] * P["R"] * P["T"] / volume(P["L0"])
    # u = 10 V: alpha = 1, m = A1 flux(P_tank, P); continuous across the critical ratio
    below, above = (_dP1(model, b * P["P_tank"] * (1 + s), 10.0) for s in (-1e-9, 1e-9))
    assert above == pytest.approx(below, rel=1e-6)
    for ratio in (0.3, b, 0.8, 0.99):
        p = ratio * P["P_tank"]
        assert _dP1(model, p, 10.0) == pytest.approx(c * P["A1"] * flux(P["P_tank"], p), rel=1e-12)
    # reversed: a muscle above the tank pressure flows back (same law, negative, area A2)
    p = 0.75e6
    assert _dP1(model, p, 10.0) == pytest.approx(-c * P["A2"] * flux(p, P["P_tank"]), rel=1e-12)
    # u = 0 V: alpha = 0, m = -A2 flux(P, P_out) (exhaust orifice)
    for p in (0.3e6, 0.15e6):
        assert _dP1(model, p, 0.0) == pytest.approx(-c * P["A2"] * flux(p, P["P_out"]), rel=1e-12)


def test_volume_rate_term_is_eq3_derivative(models, rng):
    # eq. (4): only -k2 (dV/dt / V) P depends on psi'; dV/dt = (2 D1 l + D2) dl/dt, with
    # dl1/dt = -r cos(psi) psi' (eq. (2))
    model = models["full"]
    for _ in range(5):
        psi, w = rng.uniform(-0.4, 0.4), rng.uniform(-5, 5)
        p1, u1 = rng.uniform(2e5, 7e5), rng.uniform(0, 10)
        l1 = length(1, psi)
        v_dot = (2 * P["D1"] * l1 + P["D2"]) * (-P["r"] * np.cos(psi) * w)
        expected = -P["k2"] * v_dot / volume(l1) * p1
        got = _dP1(model, p1, u1, psi, w) - _dP1(model, p1, u1, psi, 0.0)
        assert got == pytest.approx(expected, rel=1e-9)


def test_force_balance_and_outputs_match_eqs_8_9_11b(models, rng):
    model = models["full"]
    ix = model.state_index
    for _ in range(5):
        p1, p2 = rng.uniform(1.5e5, 7e5, size=2)
        psi, w, Tf = rng.uniform(-0.4, 0.4), rng.uniform(-3, 3), rng.uniform(-0.5, 0.5)
        x = np.zeros(4)
        x[[ix["P_1"], ix["P_2"], ix["q_psi"], ix["p_J"]]] = p1, p2, psi, P["J"] * w
        u = rng.uniform(0, 10, size=2)
        dx = model.f(x, u, d=[Tf])
        tau = torque(p1, p2, psi)
        assert dx[ix["p_J"]] == pytest.approx(tau - Tf - P["k_s"] * psi, rel=1e-10)   # eq. (8)
        assert dx[ix["q_psi"]] == pytest.approx(w, rel=1e-12)
        y = model.h(x, u, d=[Tf])
        assert y[model.output_index["tau"]] == pytest.approx(tau, rel=1e-10)          # eq. (9)
        assert y[model.output_index["psi"]] == pytest.approx(np.degrees(psi), rel=1e-12)
        assert (y[model.output_index["P1"]], y[model.output_index["P2"]]) == (p1, p2)
        # the held update is eq. (10) at the sub-step start
        d = model.update_held(x, u, step=H)
        assert d[0] == pytest.approx(friction_torque(tau, psi, w, p1, p2)[0], rel=1e-10)
    # locked: psi = 0, and tau is still eq. (9)
    locked = models["locked"]
    y = locked.h([4e5, 3e5], [0.0, 0.0])
    assert y[locked.output_index["psi"]] == 0.0
    assert y[locked.output_index["tau"]] == pytest.approx(torque(4e5, 3e5, 0.0), rel=1e-12)


# -- the conventions' fixed-step scheme -------------------------------------------------------

def test_simulate_reproduces_the_fixed_step_scheme(models):
    """[C]: each 1 ms sample, inputs held, is 4 classic RK4 sub-steps of 0.25 ms with T_f
    evaluated at each sub-step start and held over it; written out here with f and the
    held update only."""
    model = models["full"]
    x0 = {"P_1": 4.5e5, "P_2": 2.5e5, "q_psi": 0.05, "p_J": 0.0}
    inputs = {"u1": lambda t: 6.0 + 3.0 * np.sin(40 * t), "u2": lambda t: 3.0}
    res = simulate(pam("full"), (0.0, 0.03), inputs=inputs, x0=x0, output_interval=1e-3)
    assert res.info["method"] == "RK4" and res.info["sub_step"] == pytest.approx(H)
    x = np.array([x0[s] for s in model.state_names])
    for k in range(30):
        u = np.array([inputs["u1"](k * 1e-3), 3.0])
        for j in range(4):
            d = model.update_held(x, u, step=H)
            f = lambda xx: model.f(xx, u, d=d)   # noqa: E731
            k1 = f(x)
            k2 = f(x + H / 2 * k1)
            k3 = f(x + H / 2 * k2)
            k4 = f(x + H * k3)
            x = x + H / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        got = np.array([res[s][k + 1] for s in model.state_names])
        np.testing.assert_allclose(got, x, rtol=1e-10, atol=1e-12)
    assert np.abs(res["p_J"]).max() > 1e-6   # the joint slipped: not a trivial rest state


# -- physics tests (issue 3, section 2) -------------------------------------------------------

def test_static_pressure_is_monotone_in_u_and_linear_per_kappa():
    g = pam("locked")
    finals = []
    for u in (0, 2, 4, 6, 8, 10):
        # fixed-step RK4 (the conventions' integrator) with 5 ms sub-steps: the flow law has an
        # infinite slope at zero pressure difference, which makes adaptive solvers crawl there
        res = simulate(g, (0.0, 60.0), inputs={"u1": float(u), "u2": float(u)}, method="RK4",
                       dt=5e-3, output_interval=1.0)
        p1, p2 = res["P1"], res["P2"]
        assert abs(p1[-1] - p1[-2]) < 50 and abs(p2[-1] - p2[-2]) < 50     # steady
        assert p1[-1] == pytest.approx(p2[-1], abs=1.0)   # static pressure does not depend on V
        finals.append(p1[-1])
        # [C]: kappa was built so that the static pressure is linear in u
        assert p1[-1] == pytest.approx(static_pressure(u), abs=1e3)
    assert np.all(np.diff(finals) > 1e5)


def test_fig8_profile_free_angle_within_25_deg_and_locked_torque_within_3_nm():
    # [1] Sec. II-A: rotation range +-25 deg, torque range +-3.0 N m
    free = simulate(pam("full"), (0.0, 24.0), inputs=fig8_inputs(), output_interval=1e-3)
    locked = simulate(pam("locked"), (0.0, 24.0), inputs=fig8_inputs(), output_interval=1e-3,
                      method="RK4", dt=H)
    for res in (free, locked):
        pressures = np.concatenate([res["P1"][3000:], res["P2"][3000:]])   # after the first fill
        assert pressures.min() < 2.1e5 and pressures.max() > 6.9e5          # covers 200-700 kPa
    assert np.abs(free["psi"]).max() < 25.0
    assert np.abs(free["psi"]).max() > 5.0     # the joint does move
    assert np.abs(locked["tau"]).max() < 3.0
    assert np.all(locked["psi"] == 0.0)


def _stuck_state(ratio):
    """A state at rest with static pressures for u = (1, 1) V and |T0| = ratio * (T_s + T_p)."""
    from scipy.optimize import brentq

    ps = static_pressure(1.0)

    def excess(psi):
        T0 = torque(ps, ps, psi) - P["k_s"] * psi
        _, Fc = friction_torque(torque(ps, ps, psi), psi, 0.0, ps, ps)
        return T0 - ratio * Fc

    psi = brentq(excess, -1.0, 1.0)
    return {"P_1": ps, "P_2": ps, "q_psi": psi, "p_J": 0.0}


def test_friction_holds_the_joint_inside_the_stick_band(models):
    # pressures exactly static for the model's valves at u = 1 V
    model = models["locked"]
    from scipy.optimize import brentq
    ps = brentq(lambda p: model.f([p, p], [1.0, 1.0])[0], 1.2e5, 2.2e5, xtol=1e-9)
    x0 = {**_stuck_state(0.5), "P_1": ps, "P_2": ps}
    tau0 = torque(ps, ps, x0["q_psi"])
    T0 = tau0 - P["k_s"] * x0["q_psi"]
    assert abs(T0) < friction_torque(tau0, x0["q_psi"], 0.0, ps, ps)[1]
    res = simulate(pam("full"), (0.0, 0.02), inputs={"u1": 1.0, "u2": 1.0}, x0=x0,
                   output_interval=1e-3)
    assert np.abs(res["p_J"] / P["J"]).max() < 1e-9                   # psi' stays 0
    assert np.abs(res["q_psi"] - x0["q_psi"]).max() < 1e-12
    assert res["T_f"][1:] == pytest.approx(T0, rel=1e-6)               # stiction balances T0


def test_friction_lets_go_outside_the_stick_band():
    x0 = _stuck_state(1.5)
    res = simulate(pam("full"), (0.0, 0.02), inputs={"u1": 1.0, "u2": 1.0}, x0=x0,
                   output_interval=1e-3)
    assert np.abs(res["p_J"] / P["J"]).max() > 1e-2


def test_frictionless_is_full_with_zero_friction_and_oscillates_undamped(models, rng):
    full, free = models["full"], models["frictionless"]
    assert free.state_names == full.state_names
    x = np.column_stack([rng.uniform(1.5e5, 7e5, 4), rng.uniform(1.5e5, 7e5, 4),
                         rng.uniform(-1e-3, 1e-3, 4), rng.uniform(-0.4, 0.4, 4)])
    u = rng.uniform(0, 10, (4, 2))
    np.testing.assert_allclose(free.f(x, u), full.f(x, u, d=np.zeros((4, 1))), rtol=1e-12)
    # T_f = 0 removes c_s too ([C]): released 5.7 deg from its static equilibrium (pressures
    # static for u = 4 V, tau(psi) = k_s psi), the joint swings, damped only by the valves
    # re-regulating the pressures (eq. (4)-(5)), so the swing decays slowly
    from scipy.optimize import brentq
    ps = static_pressure(4.0)
    psi_eq = brentq(lambda s: torque(ps, ps, s) - P["k_s"] * s, -0.5, 0.5)
    x0 = {"P_1": ps, "P_2": ps, "q_psi": psi_eq - 0.1, "p_J": 0.0}
    res = simulate(pam("frictionless"), (0.0, 1.0), inputs={"u1": 4.0, "u2": 4.0}, x0=x0,
                   output_interval=1e-3)
    early, late = (np.ptp(res["psi"][a:a + 250]) for a in (0, 750))
    assert early > np.degrees(0.1)      # at least the release offset (plus the gas-spring shift)
    assert 0.8 * early < late < early
    assert np.abs(res["psi"]).max() < 25.0


@pytest.mark.parametrize("variant", ["full", "locked"])
def test_json_round_trip_keeps_the_equations(variant):
    import json

    from bondgraph.io_json import graph_from_dict, graph_to_dict
    g = pam(variant)
    back = graph_from_dict(json.loads(json.dumps(graph_to_dict(g))))
    a, b = g.equations(), back.equations()
    assert (b.name, b.f, b.h, b.held_update, b.fixed_step) == (a.name, a.f, a.h, a.held_update, a.fixed_step)
    assert dict(b.param_values) == dict(a.param_values)
