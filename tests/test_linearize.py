"""Tests of bondgraph.linearization against independent references.

References used:
- mass-spring-damper: matrices written by hand from m q'' + b q' + k q = F;
  transfer function and frequency response 1/(m s^2 + b s + k) (analytic);
  python-control (``control.ss2tf``, ``control.StateSpace``) on the hand matrices.
- pendulum: central finite differences of a plain-numpy right-hand side.
- algebraic loop: finite differences through a bracketing root solve
  (``scipy.optimize.brentq``), and the analytic implicit derivative
  dz/dx0 = -1/(1 + 3 z^2), dz/du = 1/(1 + 3 z^2).
"""
from __future__ import annotations

import json

import numpy as np
import pytest
import sympy as sp
from hypothesis import given
from hypothesis import strategies as st
from scipy.optimize import brentq

from bondgraph.errors import BondcosimError, DerivationError, ParameterError, SimulationError
from bondgraph.linearization import LinearModel, linearize
from bondgraph.system import StateEquations

control = pytest.importorskip("control")

T = sp.Symbol("t", real=True)


# ---------------------------------------------------------------------------
# Models built by hand
# ---------------------------------------------------------------------------
M, K, B_DAMP = 2.0, 8.0, 1.0


def msd() -> StateEquations:
    """Mass-spring-damper: q spring displacement (m), p momentum (N s), input force F (N)."""
    q, p, F, m, k, b = sp.symbols("q p F m k b", real=True)
    return StateEquations(
        name="msd", t=T, states=(q, p), inputs=(F,), params=(m, k, b),
        outputs=("x", "v", "F_net"),
        f=(p / m, F - k * q - b * p / m),
        h=(q, p / m, F - k * q),
        param_values={"m": M, "k": K, "b": B_DAMP},
        initial_state={"q": 0.0, "p": 0.0}, input_defaults={"F": 0.0},
        units={"q": "m", "p": "N s", "F": "N", "x": "m", "v": "m/s", "F_net": "N",
               "m": "kg", "k": "N/m", "b": "N s/m"})


def msd_hand(m=M, k=K, b=B_DAMP):
    A = np.array([[0.0, 1.0 / m], [-k, -b / m]])
    B = np.array([[0.0], [1.0]])
    C = np.array([[1.0, 0.0], [0.0, 1.0 / m], [-k, 0.0]])
    D = np.array([[0.0], [0.0], [1.0]])
    return A, B, C, D


G_ACC, L, MASS, DAMP = 9.81, 0.5, 0.3, 0.05


def pendulum() -> StateEquations:
    """Damped pendulum: angle th (rad), rate w (rad/s), torque tau (N m); output horizontal bob position."""
    th, w, tau, g, l, m, c = sp.symbols("th w tau g l m c", real=True)
    return StateEquations(
        name="pendulum", t=T, states=(th, w), inputs=(tau,), params=(g, l, m, c),
        outputs=("xb",),
        f=(w, -g / l * sp.sin(th) - c * w / (m * l**2) + tau / (m * l**2)),
        h=(l * sp.sin(th),),
        param_values={"g": G_ACC, "l": L, "m": MASS, "c": DAMP},
        initial_state={"th": 0.0, "w": 0.0}, input_defaults={"tau": 0.0})


def pendulum_f(x, u):
    th, w = x
    return np.array([w, -G_ACC / L * np.sin(th) - DAMP * w / (MASS * L**2) + u[0] / (MASS * L**2)])


def pendulum_h(x, u):
    return np.array([L * np.sin(x[0])])


def loop_model() -> StateEquations:
    """Two states, one algebraic unknown z with 0 = z - u + z^3 + x0 (plain, assumption-free symbols)."""
    x0, x1, u, z, a = sp.symbols("x0 x1 u z a")
    return StateEquations(
        name="loop", t=T, states=(x0, x1), inputs=(u,), params=(a,), outputs=("y",),
        f=(z, a * x0 - x1), h=(z**2 + x1,),
        algebraic=(z,), residuals=(z - u + z**3 + x0,),
        param_values={"a": 1.5}, initial_state={"x0": 0.2, "x1": -0.1}, input_defaults={"u": 0.7})


def loop_z(x, u):
    # Independent reference: z + z^3 = u - x0 is monotone in z, so one bracketed root.
    return brentq(lambda z: z - u[0] + z**3 + x[0], -10.0, 10.0, xtol=1e-15)


def loop_f(x, u):
    return np.array([loop_z(x, u), 1.5 * x[0] - x[1]])


def loop_h(x, u):
    return np.array([loop_z(x, u) ** 2 + x[1]])


def central_jacobians(f, x, u, eps=1e-6):
    """Central finite differences of f(x, u) w.r.t. x and u."""
    x, u = np.asarray(x, float), np.asarray(u, float)
    fx = np.column_stack([(f(x + eps * e, u) - f(x - eps * e, u)) / (2 * eps) for e in np.eye(x.size)])
    fu = np.column_stack([(f(x, u + eps * e) - f(x, u - eps * e)) / (2 * eps) for e in np.eye(u.size)])
    return fx, fu


# ---------------------------------------------------------------------------
# Mass-spring-damper
# ---------------------------------------------------------------------------
def test_msd_matrices_match_hand_derivation():
    lin = linearize(msd())
    A, B, C, D = msd_hand()
    for got, ref in ((lin.A, A), (lin.B, B), (lin.C, C), (lin.D, D)):
        np.testing.assert_allclose(got, ref, rtol=0, atol=1e-15)
    assert lin.states == ("q", "p") and lin.inputs == ("F",) and lin.outputs == ("x", "v", "F_net")
    assert lin.is_equilibrium and lin.equilibrium_residual == 0.0
    assert lin.units["p"] == "N s" and lin.units["v"] == "m/s"
    assert dict(lin.params) == {"m": M, "k": K, "b": B_DAMP}


def test_msd_params_override():
    lin = linearize(msd(), params={"k": 20.0, "m": 4.0})
    np.testing.assert_allclose(lin.A, msd_hand(m=4.0, k=20.0)[0], atol=1e-15)


def test_msd_poles_are_roots_of_characteristic_polynomial():
    # Analytic: roots of m s^2 + b s + k.
    ref = np.sort_complex(np.roots([M, B_DAMP, K]))
    np.testing.assert_allclose(linearize(msd()).poles(), ref, rtol=1e-12)


def test_msd_transfer_function_against_python_control_and_analytic():
    lin = linearize(msd())
    tf = lin.transfer_function("F", "x")
    # Analytic: X/F = 1/(m s^2 + b s + k) = (1/m) / (s^2 + (b/m) s + k/m).
    num = np.atleast_1d(np.squeeze(tf.num[0][0]))
    den = np.squeeze(tf.den[0][0])
    # ss2tf leaves round-off (~1e-16) in the leading numerator coefficients.
    np.testing.assert_allclose(num / den[0], np.r_[np.zeros(num.size - 1), 1.0 / M], rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(den / den[0], [1.0, B_DAMP / M, K / M], rtol=1e-12)
    # python-control (same library version as installed) from the hand matrices.
    A, B, C, D = msd_hand()
    ref = control.ss2tf(A, B, C[[0]], D[[0]])
    s = 1j * np.array([0.1, 1.0, 2.0, 30.0])
    np.testing.assert_allclose(tf(s), ref(s), rtol=1e-12)
    assert tf.input_labels == ["F"] and tf.output_labels == ["x"]


def test_msd_bode_against_analytic():
    lin = linearize(msd())
    omega = np.logspace(-2, 2, 401)
    w, mag, phase = lin.bode("F", "x", omega)
    g = 1.0 / (M * (1j * w) ** 2 + B_DAMP * 1j * w + K)  # analytic 1/(m s^2 + b s + k)
    np.testing.assert_allclose(w, omega)
    np.testing.assert_allclose(mag, np.abs(g), rtol=1e-12)
    # Phase runs continuously from 0 to -180 deg for this second-order lag.
    np.testing.assert_allclose(phase, np.degrees(np.unwrap(np.angle(g))), atol=1e-9)
    assert np.all(np.diff(phase) < 0)
    assert phase[0] == pytest.approx(0.0, abs=0.1) and phase[-1] == pytest.approx(-180.0, abs=0.3)


def test_msd_default_bode_grid_spans_the_poles():
    w, mag, _ = linearize(msd()).bode("F", "v")
    wn = np.sqrt(K / M)
    assert w[0] < wn / 10 < wn * 10 < w[-1] and np.all(np.diff(w) > 0)
    # Analytic velocity response: V/F = s / (m s^2 + b s + k).
    s = 1j * w
    np.testing.assert_allclose(mag, np.abs(s / (M * s**2 + B_DAMP * s + K)), rtol=1e-12)


def test_msd_feedthrough_output_frequency_response():
    # F_net = F - k q: (m s^2 + b s) / (m s^2 + b s + k), analytic.
    s = 1j * np.array([0.5, 3.0])
    got = linearize(msd()).frequency_response("F", "F_net", s.imag)
    np.testing.assert_allclose(got, (M * s**2 + B_DAMP * s) / (M * s**2 + B_DAMP * s + K), rtol=1e-12)


def test_msd_to_control_named_signals():
    lin = linearize(msd())
    sys = lin.to_control()
    A, B, C, D = msd_hand()
    for got, ref in ((sys.A, A), (sys.B, B), (sys.C, C), (sys.D, D)):
        np.testing.assert_allclose(got, ref, atol=1e-15)
    assert sys.input_labels == ["F"] and sys.output_labels == ["x", "v", "F_net"]
    assert sys.state_labels == ["q", "p"]
    # Cross-check our frequency response with python-control's on the same matrices.
    omega = np.array([0.3, 2.0, 7.0])
    ref = control.frequency_response(control.ss(A, B, C, D), omega)
    np.testing.assert_allclose(lin.frequency_response("F", "v", omega),
                               ref.complex[1, 0, :], rtol=1e-12)


def test_msd_to_dict_is_json_and_round_trips():
    lin = linearize(msd(), {"q": 0.1})
    data = json.loads(json.dumps(lin.to_dict()))
    back = LinearModel.from_dict(data)
    for attr in ("A", "B", "C", "D", "xdot", "y"):
        np.testing.assert_array_equal(getattr(back, attr), getattr(lin, attr))
    assert back.states == lin.states and dict(back.operating_point) == dict(lin.operating_point)
    assert back.is_equilibrium is False


@given(n=st.integers(0, 3), m=st.integers(0, 2), p=st.integers(0, 2), seed=st.integers(0, 2**32 - 1))
def test_linear_model_json_round_trip_any_shape(n, m, p, seed):
    rng = np.random.default_rng(seed)
    model = LinearModel(
        name="r", A=rng.normal(size=(n, n)), B=rng.normal(size=(n, m)), C=rng.normal(size=(p, n)),
        D=rng.normal(size=(p, m)), states=[f"x{i}" for i in range(n)], inputs=[f"u{i}" for i in range(m)],
        outputs=[f"y{i}" for i in range(p)], operating_point={f"x{i}": 0.5 for i in range(n)})
    back = LinearModel.from_dict(json.loads(json.dumps(model.to_dict())))
    for attr in ("A", "B", "C", "D", "xdot", "y"):
        assert getattr(back, attr).shape == getattr(model, attr).shape
        np.testing.assert_array_equal(getattr(back, attr), getattr(model, attr))
    assert (back.states, back.inputs, back.outputs) == (model.states, model.inputs, model.outputs)
    assert str(back) == str(model)


def test_wrong_matrix_shape_is_named():
    with pytest.raises(ValueError, match=r"B: expected shape \(2, 1\)"):
        LinearModel(name="bad", A=np.eye(2), B=np.ones((3, 1)), C=np.ones((1, 2)), D=np.zeros((1, 1)),
                    states=("a", "b"), inputs=("u",), outputs=("y",))


def test_str_shows_named_matrices_and_equilibrium_status():
    text = str(linearize(msd(), {"q": 0.1}))
    assert "A = d(dx/dt)/dx" in text and "F_net" in text and "q = 0.1 m" in text
    assert "NOT an equilibrium" in text and "dp/dt = -0.8" in text
    assert "\nequilibrium" in str(linearize(msd()))


def test_matrices_are_read_only():
    lin = linearize(msd())
    with pytest.raises(ValueError):
        lin.A[0, 0] = 1.0


# ---------------------------------------------------------------------------
# Pendulum (nonlinear)
# ---------------------------------------------------------------------------
def test_pendulum_at_bottom_is_analytic():
    lin = linearize(pendulum())
    # Analytic small-angle model: th'' = -(g/l) th - c/(m l^2) th' + tau/(m l^2).
    np.testing.assert_allclose(lin.A, [[0, 1], [-G_ACC / L, -DAMP / (MASS * L**2)]], rtol=1e-14)
    np.testing.assert_allclose(lin.B, [[0], [1 / (MASS * L**2)]], rtol=1e-14)
    np.testing.assert_allclose(lin.C, [[L, 0]], rtol=1e-14)
    assert lin.is_equilibrium


@pytest.mark.parametrize("x, u", [([0.7, 0.3], [0.2]), ([2.5, -1.1], [-0.4]), ([np.pi, 0.0], [0.0])])
def test_pendulum_offset_points_match_finite_differences(x, u):
    lin = linearize(pendulum(), {"th": x[0], "w": x[1], "tau": u[0]})
    fx, fu = central_jacobians(pendulum_f, x, u)
    hx, hu = central_jacobians(pendulum_h, x, u)
    for got, ref in ((lin.A, fx), (lin.B, fu), (lin.C, hx), (lin.D, hu)):
        np.testing.assert_allclose(got, ref, rtol=1e-7, atol=1e-8)
    np.testing.assert_allclose(lin.xdot, pendulum_f(np.array(x), np.array(u)), rtol=1e-14, atol=1e-14)
    assert lin.equilibrium_residual == pytest.approx(np.linalg.norm(pendulum_f(np.array(x), np.array(u))))


def test_pendulum_offset_equilibrium_is_recognised():
    th = 0.5
    tau = MASS * G_ACC * L * np.sin(th)  # static torque balance
    lin = linearize(pendulum(), {"th": th, "tau": tau})
    assert lin.is_equilibrium and lin.equilibrium_residual < 1e-12
    assert not linearize(pendulum(), {"th": th}).is_equilibrium
    np.testing.assert_allclose(lin.A[1, 0], -G_ACC / L * np.cos(th), rtol=1e-14)


# ---------------------------------------------------------------------------
# Algebraic unknowns (implicit-function theorem)
# ---------------------------------------------------------------------------
@pytest.mark.parametrize("x, u", [([0.2, -0.1], [0.7]), ([-1.3, 0.4], [2.0])])
def test_algebraic_loop_matches_finite_differences_through_root_solve(x, u):
    lin = linearize(loop_model(), {"x0": x[0], "x1": x[1], "u": u[0]})
    z = loop_z(x, u)
    assert lin.operating_point["z"] == pytest.approx(z, abs=1e-13)
    fx, fu = central_jacobians(loop_f, x, u)
    hx, hu = central_jacobians(loop_h, x, u)
    for got, ref in ((lin.A, fx), (lin.B, fu), (lin.C, hx), (lin.D, hu)):
        np.testing.assert_allclose(got, ref, rtol=1e-7, atol=1e-8)
    # Analytic implicit derivatives: dz/dx0 = -1/(1+3z^2), dz/du = 1/(1+3z^2).
    g = 1.0 / (1.0 + 3.0 * z**2)
    np.testing.assert_allclose(lin.A, [[-g, 0.0], [1.5, -1.0]], rtol=1e-13)
    np.testing.assert_allclose(lin.B, [[g], [0.0]], rtol=1e-13)
    np.testing.assert_allclose(lin.C, [[-2 * z * g, 1.0]], rtol=1e-13)
    np.testing.assert_allclose(lin.D, [[2 * z * g]], rtol=1e-13)


def test_algebraic_guess_from_operating_point_is_only_a_guess():
    a = linearize(loop_model())
    b = linearize(loop_model(), {"z": 5.0})
    assert b.operating_point["z"] == pytest.approx(a.operating_point["z"], abs=1e-13)
    np.testing.assert_allclose(b.A, a.A, rtol=1e-12)


def test_random_linear_systems_are_reproduced_exactly():
    rng = np.random.default_rng(20240611)
    for n, m, p in ((1, 1, 1), (3, 2, 2), (4, 1, 3)):
        A, B, C, D = (rng.normal(size=s) for s in ((n, n), (n, m), (p, n), (p, m)))
        x = sp.symbols(f"x0:{n}", real=True)
        u = sp.symbols(f"u0:{m}", real=True)
        X, U = sp.Matrix(x), sp.Matrix(u)
        eqs = StateEquations(
            name="rand", t=T, states=x, inputs=u, params=(), outputs=tuple(f"y{i}" for i in range(p)),
            f=tuple(sp.Matrix(A) * X + sp.Matrix(B) * U), h=tuple(sp.Matrix(C) * X + sp.Matrix(D) * U),
            initial_state={s.name: 0.0 for s in x}, input_defaults={s.name: 0.0 for s in u})
        lin = linearize(eqs, {s.name: float(v) for s, v in zip(x, rng.normal(size=n))})
        for got, ref in ((lin.A, A), (lin.B, B), (lin.C, C), (lin.D, D)):
            np.testing.assert_allclose(got, ref, rtol=1e-13, atol=1e-14)


def test_held_variables_and_time_functions():
    x, u, d, c = sp.symbols("x u d c", real=True)
    eqs = StateEquations(
        name="held", t=T, states=(x,), inputs=(u,), params=(c,), outputs=("y",),
        f=(-d * x + u,), h=(x * sp.cos(T),), held=(d,), held_update=(d,),
        param_values={"c": 2.0}, initial_state={"x": 1.0}, held_initial={"d": 3.0},
        input_functions={"u": c * sp.sin(T)})
    lin = linearize(eqs, t=0.5)
    assert lin.A[0, 0] == -3.0 and lin.operating_point["u"] == pytest.approx(2.0 * np.sin(0.5))
    assert lin.C[0, 0] == pytest.approx(np.cos(0.5))
    assert linearize(eqs, {"d": 4.0}).A[0, 0] == -4.0


# ---------------------------------------------------------------------------
# Errors
# ---------------------------------------------------------------------------
def test_unknown_operating_point_name_is_named_with_known_names():
    with pytest.raises(ParameterError, match="'qq'") as info:
        linearize(msd(), {"qq": 1.0, "F": 2.0})
    assert info.value.name == "qq"
    assert "states: q, p" in str(info.value) and "inputs: F" in str(info.value)
    assert isinstance(info.value, ValueError) and isinstance(info.value, BondcosimError)


def test_unknown_param_and_bad_values_are_all_reported():
    with pytest.raises(ParameterError) as info:
        linearize(msd(), {"q": float("nan")}, params={"kk": 1.0, "m": "heavy"})
    text = str(info.value)
    assert "'kk'" in text and "'q'" in text and "'m'" in text and "params: m, k, b" in text


def test_missing_default_is_named():
    q = sp.Symbol("q", real=True)
    eqs = StateEquations(name="nodef", t=T, states=(q,), inputs=(), params=(), outputs=(), f=(-q,), h=())
    with pytest.raises(ParameterError, match="no value for 'q'"):
        linearize(eqs)
    assert linearize(eqs, {"q": 1.0}).A[0, 0] == -1.0


@pytest.mark.parametrize("method", ["transfer_function", "bode", "frequency_response"])
def test_unknown_signal_names_list_valid_ones(method):
    lin = linearize(msd())
    args = {"frequency_response": ([1.0],)}.get(method, ())
    with pytest.raises(ParameterError, match=r"unknown input 'G'.*expected one of F"):
        getattr(lin, method)("G", "x", *args)
    with pytest.raises(ParameterError, match=r"unknown output 'y'.*expected one of x, v, F_net"):
        getattr(lin, method)("F", "y", *args)


def test_omega_on_an_imaginary_pole_is_reported():
    x, v, u = sp.symbols("x v u", real=True)
    eqs = StateEquations(name="osc", t=T, states=(x, v), inputs=(u,), params=(), outputs=("x",),
                         f=(v, -x + u), h=(x,), initial_state={"x": 0, "v": 0}, input_defaults={"u": 0})
    with pytest.raises(ParameterError, match="imaginary axis"):
        linearize(eqs).bode("u", "x", [0.5, 1.0])


def test_undeclared_symbol_is_named():
    q, w = sp.symbols("q w", real=True)
    eqs = StateEquations(name="bad", t=T, states=(q,), inputs=(), params=(), outputs=(),
                         f=(-w * q,), h=(), initial_state={"q": 1.0})
    with pytest.raises(DerivationError, match=r"f\[q\] uses undeclared symbol\(s\) w"):
        linearize(eqs)


def test_kink_at_the_point_is_not_differentiable():
    v, F = sp.symbols("v F", real=True)
    eqs = StateEquations(name="coulomb", t=T, states=(v,), inputs=(F,), params=(), outputs=(),
                         f=(F - sp.sign(v),), h=(), initial_state={"v": 0.0}, input_defaults={"F": 0.0})
    with pytest.raises(DerivationError, match=r"d f\[v\] / d v"):
        linearize(eqs)
    assert linearize(eqs, {"v": 0.3}).A[0, 0] == 0.0  # away from the kink


def test_unsolvable_and_singular_algebraic_loops():
    x, z = sp.symbols("x z", real=True)
    common = dict(t=T, states=(x,), inputs=(), params=(), outputs=(), f=(z,), h=(),
                  algebraic=(z,), initial_state={"x": 0.0})
    no_root = StateEquations(name="noroot", residuals=(z**2 + 1,), **common)
    with pytest.raises(SimulationError, match="cannot solve the algebraic loop for z"):
        linearize(no_root)
    singular = StateEquations(name="singular", residuals=(z**2 - x,), **common)
    with pytest.raises(DerivationError, match="singular"):
        linearize(singular)


def test_not_state_equations_is_rejected():
    with pytest.raises(ParameterError, match="StateEquations"):
        linearize({"f": 1})


def test_from_dict_rejects_unknown_keys():
    data = linearize(msd()).to_dict()
    data["Q"] = 1
    with pytest.raises(ParameterError, match="unknown key.*Q"):
        LinearModel.from_dict(data)
