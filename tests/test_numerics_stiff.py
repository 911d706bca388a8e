"""The linearly implicit Rosenbrock path (bondgraph.numerics.evaluate_stiff, ROS34PW2) against
independent references: its tables' order and stability on a nonlinear test problem against
scipy's DOP853, the mass-spring-damper's analytic step response (third-order convergence), a
lightly damped oscillator's exact discretisation over hundreds of periods, and scipy's Radau on
a mass with a sharply smoothed Coulomb friction, a model the RK4 path cannot afford (it would
need thousands of sub-steps per sample)."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from bondgraph import R
from bondgraph.numerics import evaluate_stiff
from bondgraph.numerics.evaluate_stiff import rosenbrock_samples
from diagnosis.errors import SimulationError
from diagnosis.recording import Experiment
from diagnosis.residuals import OutputSimulator
from plants import library
from plants.library import mass_spring_damper


def _msd_step(t):
    """x(t) of m x'' + b x' + k x = 1 from rest (m = 1, b = 0.4, k = 4), analytic."""
    wn, zeta = 2.0, 0.1
    wd = wn * np.sqrt(1 - zeta ** 2)
    return (1 - np.exp(-zeta * wn * t) * (np.cos(wd * t) + zeta * wn / wd * np.sin(wd * t))) / 4.0


def _rosenbrock_position(n):
    t = np.linspace(0.0, 2.0, n)
    exp = Experiment(t, {"F": np.ones_like(t)}, {"x": t}, {"F": "N", "x": "m"})
    m = OutputSimulator(library.build("mass-spring-damper"), exp).model
    P = m.param_vector(None).reshape(1, -1)
    X, _, most = rosenbrock_samples(m, t, np.ones((n, 1)), m.default_state.reshape(1, -1),
                                    m.default_held.reshape(1, -1), P)
    return m.h(X[:, 0], np.ones((n, 1)), t=t, p=P)[:, m.output_index["x"]], t, most


def test_rosenbrock_converges_at_third_order_to_the_analytic_step_response():
    errors = []
    for n in (101, 201, 401):
        x, t, most = _rosenbrock_position(n)
        assert most <= 4                      # |lambda| dt = 0.04 and less: one sub-step, a few
        errors.append(np.max(np.abs(x - _msd_step(t))))   # more at the start, the error check's
    assert errors[0] < 2e-6                   # of a 0.37 m response, 20 ms steps
    ratios = np.array(errors[:-1]) / np.array(errors[1:])
    np.testing.assert_allclose(ratios, 8.0, rtol=0.15)


def _sticky_mass(eps):
    g = mass_spring_damper(b=0.4)
    g.add(R("seal", effort="Fc*tanh(f/eps)", params={"Fc": 0.3, "eps": eps}, domain="translation"))
    g.connect("v_mass", "seal")
    return g


def _radau_reference(t, force, eps):
    """The same plant (m = 1, b = 0.4, k = 4, seal 0.3 tanh(v/eps)) by scipy's Radau, the force
    held over each sample."""
    x, out = np.zeros(2), [0.0]
    for k in range(t.size - 1):   # one solve per held interval: no kink inside a step
        sol = solve_ivp(lambda time, s: [s[1], force[k] - 0.4 * s[1] - 4.0 * s[0] - 0.3 * np.tanh(s[1] / eps)],
                        (t[k], t[k + 1]), x, method="Radau", rtol=1e-9, atol=1e-12)
        x = sol.y[:, -1]
        out.append(x[0])
    return np.array(out)


def test_a_sharp_coulomb_friction_runs_on_rosenbrock_and_matches_radau():
    eps = 1e-5                               # m/s: a slope of 3e4 N s/m at rest
    t = np.linspace(0.0, 3.0, 301)
    force = 1.2 * np.sin(2 * np.pi * 0.7 * t)
    exp = Experiment(t, {"F": force}, {"x": np.zeros_like(t)}, {"F": "N", "x": "m"})
    run = OutputSimulator(_sticky_mass(eps), exp).run()
    assert run.substeps < 1000              # RK4 would need 0.5 / 3e4 s sub-steps: 600 per sample
    reference = _radau_reference(t, force, eps)
    spread = np.ptp(reference)
    assert np.max(np.abs(run.outputs["x"] - reference)) < 0.01 * spread


def test_a_smooth_model_keeps_rk4_where_it_is_cheap():
    t = np.linspace(0.0, 2.0, 201)
    exp = Experiment(t, {"F": np.ones_like(t)}, {"x": t}, {"F": "N", "x": "m"})
    run = OutputSimulator(library.build("mass-spring-damper"), exp).run()
    np.testing.assert_allclose(run.outputs["x"], _msd_step(t), atol=1e-6)   # RK4's accuracy


def test_a_diverging_stiff_model_names_its_state_and_time():
    g = mass_spring_damper(b=0.4)
    g.add(R("seal", effort="-Fc*tanh(f/eps) - c*f**3", params={"Fc": 0.3, "eps": 1e-7, "c": 50.0},
            domain="translation"))
    g.connect("v_mass", "seal")
    t = np.linspace(0.0, 3.0, 301)
    exp = Experiment(t, {"F": np.ones_like(t)}, {"x": np.zeros_like(t)}, {"F": "N", "x": "m"})
    with pytest.raises(SimulationError, match=r"non-finite state\(s\) .* at t = .* \(linearly implicit ROS34PW2\)"):
        OutputSimulator(g, exp).run()


def test_the_c_sub_steps_are_the_python_loop():
    """bondgraph.numerics.evaluate_stiff_c takes the same sub-steps as the Python loop: a
    batch of three parameter sets (one shared input row per sample, a time-varying force) of a
    stiff spring (a 32 Hz mode below the 50 Hz Nyquist frequency: 10 sub-steps per sample or more) with
    a seal friction, and of the exoskeleton's drive, to rounding.  (The seal is smoothed over
    1 cm/s: a sharper one makes the stick phases amplify rounding, the sums' order included.)"""
    from bondgraph.numerics.evaluate_stiff_c import c_derivative
    stiff = mass_spring_damper(b=0.4, k=4e4)
    stiff.add(R("seal", effort="Fc*tanh(f/eps)", params={"Fc": 0.3, "eps": 1e-2}, domain="translation"))
    stiff.connect("v_mass", "seal")
    for graph, fewest in ((stiff, 10), (library.build("exoskeleton"), 1)):
        t = np.linspace(0.0, 0.5, 51)
        m = OutputSimulator(graph, Experiment(t, {}, {}, {})).model
        if c_derivative(m) is None:
            pytest.skip("no C compiler: the Python loop is the only path")
        U = np.tile(m.default_inputs, (t.size, 1))
        U[:, 0] += 1.2 * np.sin(2 * np.pi * 3.0 * t)          # the first input, whatever it is
        P = m.param_vector(None) * np.array([[1.0], [1.3], [0.7]])
        x0, d0 = np.tile(m.default_state, (3, 1)), np.tile(m.default_held, (3, 1))
        X_c, _, most_c = rosenbrock_samples(m, t, U, x0, d0, P)
        X_py, _, most_py = rosenbrock_samples(m, t, U, x0, d0, P, use_c=False)
        assert most_c == most_py >= fewest
        assert np.ptp(X_py[:, 1] - X_py[:, 0]) > 0              # the rows differ
        scale = np.maximum(np.max(np.abs(X_py), axis=(0, 1)), 1e-9)   # a state that stays at 0
        assert np.max(np.abs(X_c - X_py) / scale) < 1e-12, graph.name


def test_a_decaying_mode_that_shows_in_the_next_sample_is_followed():
    """A light mass on a stiff spring behind a large damper (m = 1e-4 kg, b = 91 N s/m,
    k = 3e4 N/m): a fast mode at -b/m = -9.1e5 1/s, which decays within any step, and a slow one
    at -k/b = -330 1/s, which a 200 Hz recording sees settle over the next samples (|lambda| dt =
    1.65).  Against the analytic response to the sampled force (matrix exponential of the linear
    system per held interval), the Rosenbrock path must follow the slow mode: one ROS2 step over
    it left 0.34 of it for the exact 0.19, and the position was 15 % of its span off."""
    m, b, k = 1e-4, 91.0, 3e4
    t = np.arange(0.0, 0.5, 0.005)
    force = np.where(np.arange(t.size) % 20 < 10, 30.0, -30.0)
    exp = Experiment(t, {"F": force}, {"x": np.zeros_like(t)}, {"F": "N", "x": "m"})
    run = OutputSimulator(mass_spring_damper(m=m, b=b, k=k), exp).run()
    x = _held_force_position(m, b, k, 0.005, force)
    assert np.max(np.abs(run.outputs["x"] - x)) < 0.01 * np.ptp(x)


def _held_force_position(m, b, k, dt, force):
    """Position of the mass-spring-damper (states x, p) under `force` held over each interval of
    `dt` s, from rest: the exact discretisation (matrix exponential) of the linear system."""
    from scipy.linalg import expm
    A = np.array([[0.0, 1.0 / m], [-k, -b / m]])
    Phi = expm(A * dt)
    Gam = np.linalg.solve(A, (Phi - np.eye(2)) @ np.array([0.0, 1.0]))   # held force over one interval
    s, x = np.zeros(2), [0.0]
    for u in force[:-1]:
        s = Phi @ s + Gam * u
        x.append(s[0])
    return np.array(x)


def test_a_lightly_damped_oscillation_keeps_its_phase_over_hundreds_of_periods():
    """24 Hz, damping ratio 0.001 (the pam's frictionless seesaw: 150 rad/s, Re lambda ~ -0.1 1/s),
    driven by a random square wave for 10 s at 1 kHz: 240 periods.  Against the exact
    discretisation, the position stays within 1 % of its span (ROS2 with h |lambda| <= 0.1, two
    sub-steps per sample, summed its phase errors to 23 %)."""
    m, k = 1.0, (2 * np.pi * 24.0) ** 2
    b = 2 * 0.001 * np.sqrt(k * m)
    t = np.arange(0.0, 10.0, 0.001)
    force = 100.0 * np.repeat(np.random.default_rng(3).choice([-1.0, 1.0], t.size // 250), 250)
    model = OutputSimulator(mass_spring_damper(m=m, b=b, k=k), Experiment(t, {}, {}, {})).model
    P = model.param_vector(None).reshape(1, -1)
    X, _, most = rosenbrock_samples(model, t, force[:, None], model.default_state.reshape(1, -1),
                                    model.default_held.reshape(1, -1), P)
    x_sim = model.h(X[:, 0], force[:, None], t=t, p=P)[:, model.output_index["x"]]
    x = _held_force_position(m, b, k, 0.001, force)
    assert most <= 8                                    # |lambda| dt = 0.15: a few sub-steps
    assert np.max(np.abs(x_sim - x)) < 0.01 * np.ptp(x)


class _Linear:
    """x' = A x as the part of a CompiledModel the sub-step uses (``f``), for a batch of one."""

    def __init__(self, A):
        self.A = np.atleast_2d(A)

    def f(self, x, u, *, t, p, d):
        return x @ self.A.T


class _Nonlinear:
    """x1' = x2, x2' = -sin x1 - 0.3 x2^3 + x2 cos x1: smooth and nonlinear (and ``jacobian``)."""

    def f(self, x, u, *, t, p, d):
        x1, x2 = x[:, 0], x[:, 1]
        return np.stack([x2, -np.sin(x1) - 0.3 * x2 ** 3 + x2 * np.cos(x1)], axis=1)

    @staticmethod
    def jacobian(x):
        x1, x2 = x[0]
        return np.array([[0.0, 1.0], [-np.cos(x1) - np.sin(x1) * x2, -0.9 * x2 ** 2 + np.cos(x1)]])


def _sub_steps(model, x, h, n, jacobian):
    W = np.eye(x.shape[1])
    for _ in range(n):
        Winv = np.linalg.inv(W - evaluate_stiff.GAMMA * h * jacobian(x))[None]
        x, _ = evaluate_stiff._python_sub_step(model, x, None, 0.0, None, None, h, Winv)
    return x


def test_the_tables_are_third_order_with_any_jacobian():
    """The tables as transcribed (Rang and Angermann 2005) on a nonlinear problem against
    scipy's DOP853 at 1e-13: the error falls 8-fold per halved step with the exact Jacobian, one
    frozen at the start, and a wrong one (a W-method keeps its order with any W)."""
    x0, T = np.array([[1.0, 0.5]]), 2.0
    reference = solve_ivp(lambda t, v: _Nonlinear().f(v[None], None, t=t, p=None, d=None)[0], (0.0, T), x0[0],
                          method="DOP853", rtol=1e-13, atol=1e-13).y[:, -1]
    jacobians = {"exact": _Nonlinear.jacobian, "frozen": lambda x: _Nonlinear.jacobian(x0),
                 "wrong": lambda x: np.array([[0.3, -2.0], [1.5, 0.7]])}
    for name, jacobian in jacobians.items():
        errors = [np.linalg.norm(_sub_steps(_Nonlinear(), x0, T / n, n, jacobian)[0] - reference)
                  for n in (80, 160, 320)]
        orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
        np.testing.assert_allclose(orders, 3.0, atol=0.1, err_msg=name)


def test_the_stability_function_is_l_stable_with_the_stated_error_constant():
    """R(z) of one sub-step on x' = lambda x (h = 1): R(-inf) = 0 (L-stable), |R(iy)| <= 1 on the
    imaginary axis (A-stable there: an undamped mode is not amplified), and |R(z) - e^z| / |z|^4
    is ERROR_CONSTANT to 3 % from the imaginary to the negative real axis, for small z."""
    def R_of(z):
        return _sub_steps(_Linear(z), np.ones((1, 1), dtype=complex), 1.0, 1, lambda x: np.atleast_2d(z))[0, 0]

    assert abs(R_of(-1e8)) < 1e-6
    assert max(abs(R_of(1j * y)) for y in np.logspace(-3, 3, 200)) <= 1.0 + 1e-12
    for angle in (90, 135, 180):
        z = 0.01 * np.exp(1j * np.deg2rad(angle))
        assert abs(R_of(z) - np.exp(z)) / abs(z) ** 4 == pytest.approx(evaluate_stiff.ERROR_CONSTANT, rel=0.03)


def test_sticking_and_sliding_within_an_interval_is_checked_by_the_error_estimate():
    """A 24 Hz oscillator (damping ratio 0.001) with a seal friction of 3 N over 1 mm/s, driven in
    bursts for 2 s at 1 kHz: it sticks and slides within sample intervals, where the Jacobian frozen
    at the interval's start is far from the true one.  Against scipy's Radau (per held interval,
    rtol 1e-10) the position stays within 1e-4 of its span; the linear sub-step rule alone (no
    error check: RTOL = inf) left 7.6e-3 (on the pam's seesaw, 8 % of the torque's span)."""
    k = (2 * np.pi * 24.0) ** 2
    b, Fc, eps = 2 * 0.001 * np.sqrt(k), 3.0, 1e-3
    graph = mass_spring_damper(m=1.0, b=b, k=k)
    graph.add(R("seal", effort="Fc*tanh(f/eps)", params={"Fc": Fc, "eps": eps}, domain="translation"))
    graph.connect("v_mass", "seal")
    t = np.arange(0.0, 2.0, 0.001)
    force = 10.0 * np.sin(2 * np.pi * 1.3 * t) * (np.sin(2 * np.pi * 0.4 * t) > 0)
    x, reference = np.zeros(2), [0.0]
    for j in range(t.size - 1):
        sol = solve_ivp(lambda time, s: [s[1], force[j] - b * s[1] - k * s[0] - Fc * np.tanh(s[1] / eps)],
                        (t[j], t[j + 1]), x, method="Radau", rtol=1e-10, atol=1e-13)
        x = sol.y[:, -1]
        reference.append(x[0])
    reference = np.array(reference)
    model = OutputSimulator(graph, Experiment(t, {}, {}, {})).model
    P = model.param_vector(None).reshape(1, -1)
    X, _, most = rosenbrock_samples(model, t, force[:, None], model.default_state.reshape(1, -1),
                                    model.default_held.reshape(1, -1), P)
    position = model.h(X[:, 0], force[:, None], t=t, p=P)[:, model.output_index["x"]]
    assert most > 7                                     # the linear rule's most: 7
    assert np.max(np.abs(position - reference)) < 1e-4 * np.ptp(reference)


def test_a_fall_from_an_unstable_rest_faster_than_the_shortest_sub_step_reaches_its_stable_rest():
    """A mass (1 kg) pushed off an unstable rest: a negative resistance -lambda (v - v^3), lambda =
    2.6e7 1/s (a Stribeck peak's falling slope on a nearly massless part grows as fast), and a force of
    1 mN from t = 5 ms, sampled at 1 kHz.  Its velocity leaves 0 and settles at the stable rest
    v = 1 + F/(2 lambda) (analytic) within a microsecond.  The linear rule's shortest sub-step
    (1 ms / 4096) has h lambda = 6; the error check now halves below it, and checks a state leaving 0
    against where the piece took it.  Before, the run settled at v = 0.068 (a spurious rest of the
    stepping), and with the halving alone the first sample after the push read 0.085."""
    lam, force = 2.6e7, 1e-3
    graph = mass_spring_damper(m=1.0, b=1e-9, k=1e-9)
    graph.add(R("drive", effort="-lam*(f - f**3)", params={"lam": lam}, domain="translation"))
    graph.connect("v_mass", "drive")
    t = np.arange(0.0, 0.02, 0.001)
    F = np.where(t >= 0.005, force, 0.0)[:, None]
    model = OutputSimulator(graph, Experiment(t, {}, {}, {})).model
    P = model.param_vector(None).reshape(1, -1)
    X, _, _ = rosenbrock_samples(model, t, F, model.default_state.reshape(1, -1), model.default_held.reshape(1, -1), P)
    v = model.h(X[:, 0], F, t=t, p=P)[:, model.output_index["v"]]
    assert np.all(v[:6] == 0.0)                          # at rest until the push (held over [5, 6) ms)
    np.testing.assert_allclose(v[6:], 1.0 + force / (2 * lam), atol=1e-6)
