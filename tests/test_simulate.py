"""bondgraph.numerics.simulation and bondgraph.numerics.results against analytic and hand-written references."""
from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import numpy as np
import pytest
import scipy.linalg
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from bondgraph.numerics import c_build
from bondgraph.errors import ExpressionError, ParameterError, SimulationError
from bondgraph.numerics.results import SimulationResult
from bondgraph.errors import UnknownNameError
from bondgraph.numerics.simulation import simulate
from bondgraph.system import StateEquations

needs_cc = pytest.mark.skipif(c_build.find_compiler() is None, reason="no C compiler")


def R(name):
    return sp.Symbol(name, real=True)


def _backends():
    return [pytest.param("c", marks=needs_cc), "numpy"]


@pytest.fixture(scope="module", autouse=True)
def _cache(tmp_path_factory):
    mp = pytest.MonkeyPatch()
    mp.setenv("BONDCOSIM_CACHE", str(tmp_path_factory.mktemp("bc_cache")))
    yield
    mp.undo()


# -- models -------------------------------------------------------------------------------

M, K, C, Q0 = 2.0, 50.0, 1.0, 0.1


@pytest.fixture(scope="module")
def msd():
    """Mass-spring-damper: q' = p/m, p' = -k q - c p/m + F."""
    t, q, p, m, k, c, F = (R(n) for n in ("t", "q", "p", "m", "k", "c", "F"))
    return StateEquations(
        name="msd", t=t, states=(q, p), inputs=(F,), params=(m, k, c), outputs=("v",),
        f=(p / m, -k * q - c * p / m + F), h=(p / m,),
        param_values={"m": M, "k": K, "c": C}, initial_state={"q": Q0},
        units={"q": "m", "p": "N s", "F": "N", "v": "m/s", "m": "kg", "k": "N/m", "c": "N s/m"})


@pytest.fixture(scope="module")
def first_order():
    """x' = -a x + u."""
    t, x, u, a = R("t"), R("x"), R("u"), R("a")
    return StateEquations(name="lag", t=t, states=(x,), inputs=(u,), params=(a,), outputs=("y",),
                          f=(-a * x + u,), h=(2 * x,), param_values={"a": 3.0},
                          units={"x": "m", "u": "m/s", "y": "m"})


def _held_model(fixed_step=0.01):
    """Sample-and-hold: xs <- x and clock c <- c + step at each sub-step start;
    x' = -a xs - b x + u."""
    t, x, u, a, b, xs, clk = (R(n) for n in ("t", "x", "u", "a", "b", "xs", "clk"))
    step = sp.Symbol("h_step", positive=True)
    return StateEquations(
        name="sah", t=t, states=(x,), inputs=(u,), params=(a, b), outputs=("y",),
        f=(-a * xs - b * x + u,), h=(x - xs,), held=(xs, clk), held_update=(x, clk + step),
        step=step, fixed_step=fixed_step, param_values={"a": 4.0, "b": 1.0},
        initial_state={"x": 1.0}, held_initial={"xs": 0.0, "clk": 0.0},
        units={"x": "V", "u": "V/s", "y": "V", "xs": "V", "clk": "s"})


# -- smooth models ------------------------------------------------------------------------

@pytest.mark.parametrize("backend", _backends())
def test_mass_spring_damper_matches_analytic(msd, backend):
    res = simulate(msd, (0.0, 10.0), backend=backend, output_interval=0.01)
    # free response of an underdamped oscillator from (q0, 0):
    # q = q0 exp(-zeta wn t) (cos wd t + zeta wn / wd sin wd t)
    wn = np.sqrt(K / M)
    zeta = C / (2 * np.sqrt(K * M))
    wd = wn * np.sqrt(1 - zeta**2)
    t = res.t
    q = Q0 * np.exp(-zeta * wn * t) * (np.cos(wd * t) + zeta * wn / wd * np.sin(wd * t))
    v = -Q0 * wn**2 / wd * np.exp(-zeta * wn * t) * np.sin(wd * t)
    assert res.info["method"] == "LSODA"
    np.testing.assert_allclose(res["q"], q, atol=1e-7)
    np.testing.assert_allclose(res["v"], v, atol=1e-6)
    assert t[0] == 0.0 and t[-1] == 10.0 and t.size == 1001
    assert res.units["q"] == "m" and res.kinds["v"] == "output"


@pytest.mark.parametrize("backend", _backends())
def test_stiff_linear_system_matches_expm(backend):
    t, x1, x2, x3, lam = R("t"), R("x1"), R("x2"), R("x3"), R("lam")
    A = sp.Matrix([[-1, 1, 0], [0, -100, 50], [0, 0, -lam]])
    X = sp.Matrix([x1, x2, x3])
    eqs = StateEquations(name="stiff", t=t, states=(x1, x2, x3), inputs=(), params=(lam,),
                         outputs=(), f=tuple(A * X), h=(), param_values={"lam": 1e4},
                         initial_state={"x1": 1.0, "x2": 1.0, "x3": 1.0})
    res = simulate(eqs, (0.0, 2.0), backend=backend, output_interval=0.05)
    assert res.info["method"] == "Radau" and res.info["stiffness"] > 1e3
    An = np.array(A.subs(lam, 1e4), dtype=float)
    ref = np.array([scipy.linalg.expm(An * ti) @ np.ones(3) for ti in res.t])
    for j, name in enumerate(("x1", "x2", "x3")):
        np.testing.assert_allclose(res[name], ref[:, j], rtol=1e-6, atol=1e-9)


def _lag_reference(t, a=3.0, w=2.0):
    # x' = -a x + sin(w t), x(0) = 0
    return (a * np.sin(w * t) - w * np.cos(w * t) + w * np.exp(-a * t)) / (a**2 + w**2)


@pytest.mark.parametrize("spec", ["sin(2*t)", lambda t: np.sin(2 * t), sp.sin(2 * sp.Symbol("t"))],
                         ids=["string", "callable", "sympy"])
def test_input_kinds_match_analytic(first_order, spec):
    res = simulate(first_order, (0.0, 3.0), inputs={"u": spec}, backend="numpy",
                   output_interval=0.1)
    np.testing.assert_allclose(res["x"], _lag_reference(res.t), atol=1e-8)
    np.testing.assert_allclose(res["u"], np.sin(2 * res.t), rtol=1e-14)
    np.testing.assert_allclose(res["y"], 2 * res["x"], rtol=1e-15)


def test_input_functions_are_the_default(first_order):
    eqs = StateEquations(**{**{f: getattr(first_order, f) for f in (
        "name", "t", "states", "inputs", "params", "outputs", "f", "h", "param_values", "units")},
        "input_functions": {"u": sp.sin(2 * first_order.t)}})
    res = simulate(eqs, (0.0, 3.0), backend="numpy", output_interval=0.1)
    np.testing.assert_allclose(res["x"], _lag_reference(res.t), atol=1e-8)


@pytest.mark.parametrize("backend", _backends())
def test_table_input_is_zero_order_hold(backend):
    t, x, u = R("t"), R("x"), R("u")
    eqs = StateEquations(name="integrator", t=t, states=(x,), inputs=(u,), params=(),
                         outputs=(), f=(u,), h=())
    times, values = [0.0, 0.5, 1.25], [1.0, -2.0, 3.0]
    res = simulate(eqs, (0.0, 2.0), inputs={"u": (times, values)}, backend=backend,
                   output_interval=0.25)
    # exact integral of the step signal: slope 1 to 0.5, -2 to 1.25, then 3
    ref = np.interp(res.t, [0.0, 0.5, 1.25, 2.0], [0.0, 0.5, -1.0, 1.25])
    np.testing.assert_allclose(res["x"], ref, atol=1e-9)
    np.testing.assert_array_equal(res["u"], np.where(res.t < 0.5, 1.0, np.where(res.t < 1.25, -2.0, 3.0)))


def test_a_table_restarts_the_integration_only_where_it_steps(msd):
    """A 1 kHz recording of levels held over 50 samples integrates exactly as the table of its steps
    alone: samples that repeat the value before them are no restart (each one was a solve_ivp run)."""
    rng = np.random.default_rng(7)
    t = np.arange(2001) * 1e-3
    levels = np.repeat(rng.uniform(-1.0, 1.0, 41), 50)[:t.size]
    steps = np.concatenate([[0], np.flatnonzero(np.diff(levels)) + 1])
    dense = simulate(msd, (0.0, 2.0), inputs={"F": (t, levels)}, output_interval=0.01)
    sparse = simulate(msd, (0.0, 2.0), inputs={"F": (t[steps], levels[steps])}, output_interval=0.01)
    np.testing.assert_array_equal(dense["v"], sparse["v"])
    assert dense.info["nfev"] == sparse.info["nfev"]


# -- fixed-step models ---------------------------------------------------------------------

@pytest.mark.parametrize("backend", _backends())
def test_sample_and_hold_matches_hand_loop(backend):
    eqs = _held_model(fixed_step=0.01)
    res = simulate(eqs, (0.0, 1.0), inputs={"u": ([0.0, 0.5], [1.0, -1.0])},
                   output_interval=0.05, backend=backend)
    assert res.info["method"] == "RK4" and res.info["sub_step"] == pytest.approx(0.01)
    # hand-written loop: held values sampled at each sub-step start, RK4 over the sub-step,
    # input held over each output interval
    a, b, h = 4.0, 1.0, 0.01
    x, xs, clk = 1.0, 0.0, 0.0
    X, XS, CLK = [x], [xs], [clk]
    for k in range(20):
        u = 1.0 if 0.05 * k < 0.5 - 1e-12 else -1.0
        for _ in range(5):
            xs, clk = x, clk + h
            f = lambda xx: -a * xs - b * xx + u  # noqa: E731
            k1 = f(x)
            k2 = f(x + h / 2 * k1)
            k3 = f(x + h / 2 * k2)
            k4 = f(x + h * k3)
            x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        X.append(x), XS.append(xs), CLK.append(clk)
    np.testing.assert_allclose(res["x"], X, rtol=1e-12)
    np.testing.assert_allclose(res["xs"], XS, rtol=1e-12)
    np.testing.assert_allclose(res["clk"], CLK, rtol=1e-12)
    np.testing.assert_allclose(res["y"], np.array(X) - np.array(XS), atol=1e-14)
    assert res.kinds["xs"] == "held"


def test_dt_smaller_than_fixed_step_refines_sub_steps():
    res = simulate(_held_model(fixed_step=0.01), (0.0, 0.2), dt=0.004, output_interval=0.02,
                   backend="numpy")
    # ceil(0.02 / 0.004) = 5 sub-steps of 0.004 s per output interval; clock counts them
    assert res.info["sub_step"] == pytest.approx(0.004)
    np.testing.assert_allclose(res["clk"], res.t, atol=1e-12)


# -- algebraic loop in a simulation -------------------------------------------------------

@needs_cc
def test_algebraic_loop_simulation_backends_agree():
    t, x, u, z = R("t"), R("x"), R("u"), R("z")
    eqs = StateEquations(name="loopsim", t=t, states=(x,), inputs=(u,), params=(), outputs=("w",),
                         f=(-z,), h=(2 * z,), algebraic=(z,), residuals=(z - sp.cos(x * z) - u,),
                         initial_state={"x": 1.0}, input_defaults={"u": 0.2})
    rc = simulate(eqs, (0.0, 2.0), backend="c", output_interval=0.1)
    rn = simulate(eqs, (0.0, 2.0), backend="numpy", output_interval=0.1)
    np.testing.assert_allclose(rc["x"], rn["x"], rtol=1e-9)
    z = rc["z"]
    assert np.max(np.abs(z - np.cos(rc["x"] * z) - 0.2)) < 1e-12
    np.testing.assert_allclose(rc["w"], 2 * z, rtol=1e-15)


@needs_cc
def test_held_model_with_algebraic_loop_backends_agree():
    t, x, v, u, z, xs = (R(n) for n in ("t", "x", "v", "u", "z", "xs"))
    step = sp.Symbol("h_step", positive=True)
    eqs = StateEquations(
        name="heldloop", t=t, states=(x, v), inputs=(u,), params=(), outputs=("w",),
        f=(v, -z - 0.5 * v + xs), h=(z,), algebraic=(z,), residuals=(z - sp.tanh(3 * x * z) - u * x,),
        held=(xs,), held_update=(-0.2 * x + 0 * step,), fixed_step=0.01,
        initial_state={"x": 1.0}, input_defaults={"u": 0.3})
    rc = simulate(eqs, (0.0, 0.5), backend="c", output_interval=0.05)
    rn = simulate(eqs, (0.0, 0.5), backend="numpy", output_interval=0.05)
    for name in ("x", "v", "z", "xs", "w"):
        np.testing.assert_allclose(rc[name], rn[name], rtol=1e-12, atol=1e-14)
    assert np.max(np.abs(rc["z"] - np.tanh(3 * rc["x"] * rc["z"]) - 0.3 * rc["x"])) < 1e-12


# -- errors ---------------------------------------------------------------------------------

def test_bad_inputs_raise_named_errors(first_order):
    with pytest.raises(UnknownNameError, match=r"unknown input 'force'.*known inputs are u") as info:
        simulate(first_order, (0, 1), inputs={"force": 1.0}, backend="numpy")
    assert info.value.name == "force" and info.value.known == ["u"]
    with pytest.raises(ExpressionError, match=r"input 'u'.*'sin\(2\*t'") as info:
        simulate(first_order, (0, 1), inputs={"u": "sin(2*t"}, backend="numpy")
    assert info.value.expression == "sin(2*t"
    with pytest.raises(ExpressionError, match=r"input 'u'.*unknown name\(s\) q"):
        simulate(first_order, (0, 1), inputs={"u": "q * t"}, backend="numpy")
    with pytest.raises(ValueError, match=r"x0: expected shape \(1,\).*found \(2,\)"):
        simulate(first_order, (0, 1), x0=[1.0, 2.0], backend="numpy")
    with pytest.raises(ParameterError, match="unknown parameter 'alpha'.*known parameters are a"):
        simulate(first_order, (0, 1), params={"alpha": 1.0}, backend="numpy")
    with pytest.raises(ValueError, match="table must be"):
        simulate(first_order, (0, 1), inputs={"u": ([0, 1, 2], [1, 2])}, backend="numpy")
    with pytest.raises(ValueError, match="t_span"):
        simulate(first_order, (1, 0), backend="numpy")
    with pytest.raises(ValueError, match="method"):
        simulate(first_order, (0, 1), method="Euler", backend="numpy")
    with pytest.raises(ValueError, match="not smooth.*RK4"):
        simulate(_held_model(), (0, 1), method="LSODA", backend="numpy")


def test_non_finite_state_is_named():
    t, w = R("t"), R("w")
    # w' = -1/sqrt(w) reaches 0 at t = 2/3 and then has no real value
    eqs = StateEquations(name="dry", t=t, states=(w,), inputs=(), params=(), outputs=(),
                         f=(-1 / sp.sqrt(w),), h=(), initial_state={"w": 1.0}, fixed_step=0.01)
    with pytest.raises(SimulationError, match=r"non-finite .* of w at t = ") as info:
        simulate(eqs, (0.0, 1.0), backend="numpy")
    assert 0.6 < info.value.time <= 0.7


# -- results --------------------------------------------------------------------------------

def test_csv_round_trip(msd, tmp_path):
    res = simulate(msd, (0.0, 1.0), backend="numpy", output_interval=0.1, x0={"q": 0.05})
    path = tmp_path / "run.csv"
    res.to_csv(path)
    header = path.read_text().splitlines()[0]
    assert header == "time [s],q [m],p [N s],F [N],v [m/s]"
    back = SimulationResult.from_csv(path)
    assert back.names == res.names and dict(back.units) == dict(res.units)
    np.testing.assert_array_equal(back.t, res.t)
    for name in res.names:
        np.testing.assert_array_equal(back[name], res[name])
    bad = tmp_path / "bad.csv"
    bad.write_text("seconds,q\n0,1\n")
    with pytest.raises(ValueError, match="first column must be 'time"):
        SimulationResult.from_csv(bad)


def test_result_access_and_immutability(msd):
    res = simulate(msd, (0.0, 0.5), backend="numpy", output_interval=0.1)
    with pytest.raises(KeyError, match="no signal 'z'.*q, p, F, v"):
        res["z"]
    with pytest.raises(AttributeError):
        res.t = None
    with pytest.raises(ValueError):
        res["q"][0] = 1.0
    assert res.names_of("state") == ("q", "p")


def test_plot_groups_by_unit(msd):
    res = simulate(msd, (0.0, 0.5), backend="numpy", output_interval=0.1)
    fig = res.plot(["q", "v", "F"])
    axes = fig.get_axes()
    assert len(axes) == 3
    assert [ln.get_label() for ln in axes[0].get_lines()] == ["q [m]"]
    assert axes[-1].get_xlabel() == "t [s]"
    import matplotlib.pyplot as plt
    plt.close(fig)


def test_system_with_equations_method_and_progress(first_order, capsys):
    class Graph:
        def equations(self):
            return first_order

    res = simulate(Graph(), (0.0, 1.0), inputs={"u": 1.0}, backend="numpy", progress=True)
    # x' = -3 x + 1, x(0) = 0
    np.testing.assert_allclose(res["x"], (1 - np.exp(-3 * res.t)) / 3, atol=1e-8)
    assert "100.0 %" in capsys.readouterr().err


_names = st.text(st.characters(whitelist_categories=("L", "N"), whitelist_characters="_ ,'\""),
                 min_size=1, max_size=8).map(str.strip).filter(lambda n: n and n != "time")
_units = st.sampled_from(["", "m", "N s", "rad/s", "kg m^2", "Pa", "1"])


@settings(max_examples=30, deadline=None)
@given(data=st.data(), n=st.integers(1, 6))
def test_csv_round_trip_property(tmp_path_factory, data, n):
    names = data.draw(st.lists(_names, min_size=1, max_size=4, unique=True))
    floats = st.floats(allow_nan=True, allow_infinity=False, width=64)
    t = np.sort(np.array(data.draw(st.lists(st.floats(-1e6, 1e6), min_size=n, max_size=n))))
    signals = {nm: data.draw(st.lists(floats, min_size=n, max_size=n)) for nm in names}
    units = {nm: data.draw(_units) for nm in names}
    res = SimulationResult(t, signals, units=units)
    path = tmp_path_factory.mktemp("csv") / "r.csv"
    res.to_csv(path)
    back = SimulationResult.from_csv(path)
    assert back.names == res.names and dict(back.units) == units
    np.testing.assert_array_equal(back.t, res.t)
    for nm in names:
        np.testing.assert_array_equal(back[nm], res[nm])


def test_a_solver_grinding_towards_a_singularity_stops_with_a_named_error():
    """pam-frictionless from vented muscles swings towards the angle where a muscle
    volume vanishes; LSODA's steps collapse there.  The budget turns that into an error."""
    import plants.library as library
    from bondgraph.errors import SimulationError
    with pytest.raises(SimulationError, match=r"gave up after 3000 right-hand-side evaluations "
                                              r"at t = .* fastest-changing states") as info:
        simulate(library.build("pam-frictionless"), (0.0, 2.0), max_nfev=3000)
    assert 0.0 < info.value.time < 2.0


def test_an_implicit_method_given_a_non_finite_jacobian_stops_with_a_named_error():
    """pam-frictionless from vented muscles starts with its chambers at atmospheric pressure, where
    the valves' flow law has the square root of 1 - (P/P_u)^((k-1)/k) at 0: its slope is infinite,
    and the Jacobian of P_1' and P_2' not finite (the closed valves make it 0 * inf).  Radau needs
    that Jacobian; it failed in scipy's LU with a bare ValueError."""
    import plants.library as library
    from bondgraph.errors import SimulationError
    with pytest.raises(SimulationError, match=r"non-finite Jacobian of the time derivative of P_1, P_2 at t = 0 s, "
                                              r"which Radau needs.*method='LSODA'") as info:
        simulate(library.build("pam-frictionless"), (0.0, 0.1), method="Radau")
    assert info.value.time == 0.0
