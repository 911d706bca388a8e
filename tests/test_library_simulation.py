"""Simulations of the textbook graphs against analytic solutions.

References: second-order step responses (Ogata, *Modern Control
Engineering*, 5th ed., sec. 5-3); first-order RC/inertia responses; the
exact step response of a linear system ``x(t) = A^-1 (e^{At} - I) B u``
(matrix exponential, scipy.linalg.expm) with matrices written by hand.
"""
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.linalg import expm
from scipy.optimize import brentq

from plants import library
from bondgraph.numerics.simulation import simulate


def _second_order_step(t, gain, wn, zeta):
    wd = wn * np.sqrt(1 - zeta**2)
    return gain * (1 - np.exp(-zeta * wn * t) * (np.cos(wd * t) + zeta * wn / wd * np.sin(wd * t)))


def test_mass_spring_damper_step():
    res = simulate(library.build("mass-spring-damper"), (0, 10), output_interval=0.01)
    m, b, k, F = 1.0, 0.4, 4.0, 1.0
    x = _second_order_step(res.t, F / k, np.sqrt(k / m), b / (2 * np.sqrt(k * m)))
    assert np.max(np.abs(res["x"] - x)) < 1e-7
    assert res.units["x"] == "m"


def test_rlc_capacitor_voltage():
    res = simulate(library.build("rlc"), (0, 0.1), output_interval=1e-4)
    R, L, C = 10.0, 0.1, 1e-3
    v = _second_order_step(res.t, 1.0, 1 / np.sqrt(L * C), R / 2 * np.sqrt(C / L))
    assert np.max(np.abs(res["v_C"] - v)) < 1e-7


def test_dc_motor_matches_matrix_exponential():
    Ra, La, km, Jm, bm, n, bL, V = 1.0, 0.5e-3, 0.05, 1e-4, 1e-5, 0.1, 2e-3, 12.0
    # states (i, w): La di/dt = V - Ra i - km w ; Jm dw/dt = km i - (bm + n^2 bL) w
    A = np.array([[-Ra / La, -km / La], [km / Jm, -(bm + n**2 * bL) / Jm]])
    B = np.array([1 / La, 0.0])
    res = simulate(library.build("dc-motor"), (0, 0.2), output_interval=1e-3)
    exact = np.array([np.linalg.solve(A, (expm(A * t) - np.eye(2)) @ B * V) for t in res.t])
    assert np.allclose(res["i"], exact[:, 0], rtol=1e-6, atol=1e-6)
    assert np.allclose(res["w_L"], n * exact[:, 1], rtol=1e-6, atol=1e-6)


def test_coupled_tanks_reach_torricelli_steady_state():
    res = simulate(library.build("coupled-tanks"), (0, 20000), output_interval=100.0)
    Q, a12, a2, g = 2e-4, 5e-5, 4e-5, 9.81
    h2 = (Q / a2) ** 2 / (2 * g)             # Q = a2 sqrt(2 g h2)
    h1 = h2 + (Q / a12) ** 2 / (2 * g)       # Q = a12 sqrt(2 g (h1 - h2))
    assert res["h1"][-1] == pytest.approx(h1, rel=1e-4)
    assert res["h2"][-1] == pytest.approx(h2, rel=1e-4)
    assert res["Q_out"][-1] == pytest.approx(Q, rel=1e-4)


def test_geared_inertias_reflected_inertia():
    res = simulate(library.build("geared-inertias"), (0, 2), output_interval=0.01)
    J1, J2, n, b, tau = 0.01, 0.5, 0.2, 0.05, 1.0
    w1 = tau / b * (1 - np.exp(-b * res.t / (J1 + n**2 * J2)))
    assert np.max(np.abs(res["w1"] - w1)) < 1e-7
    assert np.max(np.abs(res["w2"] - n * w1)) < 1e-7


def test_linear_resistor_loop_is_a_thevenin_rc():
    res = simulate(library.build("resistor-loop"), (0, 5), output_interval=0.01)
    R1, R2, R3, C, V = 1.0, 2.0, 3.0, 0.5, 1.0
    v_th, r_th = V * R2 / (R1 + R2), R1 * R2 / (R1 + R2) + R3
    assert np.max(np.abs(res["v_C"] - v_th * (1 - np.exp(-res.t / (r_th * C))))) < 1e-8


@pytest.mark.parametrize("backend", ["c", "numpy"])
def test_nonlinear_resistor_loop_matches_independent_solution(backend):
    """The loop solved by Newton inside the evaluator vs a brentq solve inside a Python RHS."""
    R1, R2, R3, a3, C, V = 1.0, 2.0, 3.0, 0.5, 0.5, 1.0

    def branch_current(vc):
        # i3 = (V - vm)/R1 - vm/R2 and vm - vc = R3 i3 + a3 i3^3: solve for vm
        def residual(vm):
            i3 = (V - vm) / R1 - vm / R2
            return vm - vc - R3 * i3 - a3 * i3**3
        vm = brentq(residual, -10, 10, xtol=1e-15)
        return (V - vm) / R1 - vm / R2

    t = np.linspace(0, 3, 31)
    ref = solve_ivp(lambda _, q: [branch_current(q[0] / C)], (0, 3), [0.0], t_eval=t, rtol=1e-11, atol=1e-13)
    res = simulate(library.build("resistor-loop-nl"), (0, 3), output_interval=0.1, backend=backend)
    assert np.max(np.abs(res["v_C"] - ref.y[0] / C)) < 1e-7


def test_backends_agree_on_every_builtin_model(rng):
    from bondgraph.numerics import compile_model
    for name in library.names():
        eqs = library.build(name).equations()
        c, py = compile_model(eqs, backend="c"), compile_model(eqs, backend="numpy")
        x = rng.uniform(0.001, 0.01, (7, len(eqs.states)))
        u = rng.uniform(0.0, 1.0, (7, len(eqs.inputs)))
        assert np.allclose(c.f(x, u), py.f(x, u), rtol=1e-12, atol=1e-14), name
        assert np.allclose(c.h(x, u), py.h(x, u), rtol=1e-12, atol=1e-14), name
