"""Compiled evaluators (bondgraph.numerics.codegen_c, bondgraph.numerics.evaluate) against independent references.

References: plain sympy ``xreplace`` + ``evalf`` of the same expressions (exact
rational arithmetic up to float inputs), hand-written formulas, and central
finite differences for the implicit-function Jacobian.
"""
from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

from bondgraph.numerics import c_build, codegen_c
from bondgraph.errors import CompilationError, ExpressionError, ParameterError, SimulationError
from bondgraph.numerics.evaluate import compile_model
from bondgraph.system import StateEquations

BACKENDS = ["c", "numpy"]
needs_cc = pytest.mark.skipif(c_build.find_compiler() is None, reason="no C compiler")


def R(name):
    return sp.Symbol(name, real=True)


@pytest.fixture(scope="module", autouse=True)
def _cache(tmp_path_factory):
    mp = pytest.MonkeyPatch()
    mp.setenv("BONDCOSIM_CACHE", str(tmp_path_factory.mktemp("bc_cache")))
    yield
    mp.undo()


def _backends():
    return [pytest.param("c", marks=needs_cc), "numpy"]


# -- models -------------------------------------------------------------------------

def kitchen_sink(name="sink"):
    """Every function the contract allows, with time, inputs, params and a held value."""
    t, x0, x1, x2 = R("t"), R("x0"), R("x1"), R("x2")
    u0, u1, a, b, c, d0 = R("u0"), R("u1"), R("a"), R("b"), R("c"), R("d0")
    step = sp.Symbol("h_step", positive=True)
    f = (
        sp.Piecewise((a * x0**2, x0 > 0), (-b * sp.sin(x1), True))
        + sp.sign(x2) * sp.Abs(x1)**1.5 + sp.Heaviside(x0 - 0.1) * u0 + d0,
        sp.exp(-x1**2) * sp.cos(c * t) + sp.log(1 + x2**2) + sp.Max(x0, x1, u1) - sp.Min(x2, 0.3),
        sp.sqrt(sp.Abs(x0) + 1) * sp.tanh(x1) + sp.atan(x2) + sp.atan2(x1, x0)
        + sp.tan(sp.Float(0.3) * x2) + x0**3 / 3 - sp.pi * u1 / (1 + x2**2),
    )
    h = (x0 * x1 + sp.E, sp.Piecewise((x2, x2 < 0.5)), x0**sp.Float(2.5) / (1 + x1**2))
    return StateEquations(
        name=name, t=t, states=(x0, x1, x2), inputs=(u0, u1), params=(a, b, c),
        outputs=("y0", "y1", "y2"), f=f, h=h, held=(d0,), held_update=(d0 + step * x1,),
        step=step, fixed_step=0.01,
        param_values={"a": 1.5, "b": -0.7, "c": 2.0}, input_defaults={"u0": 0.3, "u1": -0.2},
        held_initial={"d0": 0.25})


def loop_model():
    """Scalar nonlinear algebraic loop z = cos(x0 z) + u."""
    t, x0, x1, u, z, a = R("t"), R("x0"), R("x1"), R("u"), R("zloop"), R("a")
    return StateEquations(
        name="loop", t=t, states=(x0, x1), inputs=(u,), params=(a,), outputs=("y",),
        f=(x1, -a * z * x0 + sp.sin(t)), h=(z * x1,), algebraic=(z,),
        residuals=(z - sp.cos(x0 * z) - u,), param_values={"a": 2.0}, input_defaults={"u": 0.5})


def loop2_model():
    """Two coupled unknowns: z1 + 0.1 z2^3 = x0, z2 - 0.5 sin(z1) = x1 (needs pivoting-free
    elimination of a full 2x2 system)."""
    t, x0, x1, z1, z2 = R("t"), R("x0"), R("x1"), R("z1"), R("z2")
    return StateEquations(
        name="loop2", t=t, states=(x0, x1), inputs=(), params=(), outputs=("s",),
        f=(-z1, z2 - x0), h=(z1 + z2,), algebraic=(z1, z2),
        residuals=(z1 + sp.Float(0.1) * z2**3 - x0, z2 - sp.Float(0.5) * sp.sin(z1) - x1))


def _reference(eqs, exprs, x, u, p, d, t):
    """Evaluate sympy expressions row by row with xreplace + evalf (30 digits)."""
    out = np.empty((x.shape[0], len(exprs)))
    for i in range(x.shape[0]):
        values = {eqs.t: t[i]}
        for syms, row in ((eqs.states, x[i]), (eqs.inputs, u[i]), (eqs.params, p[i]),
                          (eqs.held, d[i])):
            values.update({s: sp.Float(float(v), 30) for s, v in zip(syms, row)})
        for k, e in enumerate(exprs):
            v = sp.sympify(e).xreplace(values).evalf(30)
            out[i, k] = float(v) if v.is_real else np.nan
    return out


def _random_batch(model, n, rng):
    x = rng.uniform(-1.2, 1.2, size=(n, len(model.state_names)))
    u = rng.uniform(-1, 1, size=(n, len(model.input_names)))
    p = model.default_params * rng.uniform(0.5, 1.5, size=(n, len(model.param_names)))
    d = rng.uniform(-1, 1, size=(n, len(model.held_names)))
    t = rng.uniform(0, 5, size=n)
    return x, u, p, d, t


# -- explicit functions ----------------------------------------------------------------

@pytest.mark.parametrize("backend", _backends())
def test_f_h_match_sympy(backend):
    eqs = kitchen_sink()
    model = compile_model(eqs, backend=backend)
    rng = np.random.default_rng(1)
    x, u, p, d, t = _random_batch(model, 40, rng)
    f = model.f(x, u, t=t, p=p, d=d)
    y = model.h(x, u, t=t, p=p, d=d)
    assert f.shape == (40, 3) and y.shape == (40, 3)
    np.testing.assert_allclose(f, _reference(eqs, eqs.f, x, u, p, d, t), rtol=1e-12, atol=1e-13)
    ref_y = _reference(eqs, eqs.h, x, u, p, d, t)
    # y1 = Piecewise((x2, x2 < 0.5)) has no value for x2 >= 0.5: NaN in both
    np.testing.assert_array_equal(np.isnan(y), np.isnan(ref_y))
    np.testing.assert_allclose(y, ref_y, rtol=1e-12, atol=1e-13)


@needs_cc
def test_c_and_numpy_agree_with_broadcast_arguments():
    eqs = kitchen_sink()
    mc, mn = compile_model(eqs, backend="c"), compile_model(eqs, backend="numpy")
    rng = np.random.default_rng(2)
    x, *_ = _random_batch(mc, 64, rng)
    for kwargs in ({}, {"t": 1.3, "p": {"a": 0.2}}, {"d": [0.1]}, {"t": np.linspace(0, 1, 64)}):
        for name in ("f", "h", "jac_x"):
            a, b = getattr(mc, name)(x, **kwargs), getattr(mn, name)(x, **kwargs)
            np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-13, equal_nan=True)
    np.testing.assert_allclose(mc.update_held(x, step=0.01), mn.update_held(x, step=0.01), rtol=1e-14)


@pytest.mark.parametrize("backend", _backends())
def test_jacobian_matches_sympy(backend):
    eqs = kitchen_sink()
    model = compile_model(eqs, backend=backend)
    rng = np.random.default_rng(3)
    x, u, p, d, t = _random_batch(model, 10, rng)
    J = model.jac_x(x, u, t=t, p=p, d=d)
    Jsym = sp.Matrix(eqs.f).jacobian(eqs.states)
    ref = _reference(eqs, list(Jsym), x, u, p, d, t).reshape(10, 3, 3)
    np.testing.assert_allclose(J, ref, rtol=1e-11, atol=1e-12)


@pytest.mark.parametrize("backend", _backends())
def test_shapes_follow_input_and_params_per_row(backend):
    model = compile_model(kitchen_sink(), backend=backend)
    rng = np.random.default_rng(4)
    x, u, p, d, t = _random_batch(model, 5, rng)
    batch = model.f(x, u, t=t, p=p, d=d)
    for i in range(5):
        one = model.f(x[i], u[i], t=t[i], p=dict(zip(model.param_names, p[i])), d=d[i])
        assert one.shape == (3,)
        np.testing.assert_allclose(one, batch[i], rtol=1e-15)
    assert model.jac_x(x[0]).shape == (3, 3)
    assert model.h(x).shape == (5, 3)


@pytest.mark.parametrize("backend", _backends())
def test_held_update_uses_step(backend):
    model = compile_model(kitchen_sink(), backend=backend)
    x = np.array([[0.1, 0.4, -0.3], [0.0, -2.0, 1.0]])
    # d+ = d0 + step * x1 (hand-computed)
    np.testing.assert_allclose(model.update_held(x, d=[0.25], step=0.1), [[0.29], [0.05]], rtol=1e-15)


@needs_cc
def test_split_functions_give_the_same_numbers(monkeypatch):
    eqs = kitchen_sink("sink_split")
    reference = compile_model(eqs, backend="numpy")
    monkeypatch.setattr(codegen_c, "SPLIT_STATEMENTS", 2)
    source = codegen_c.generate_source(eqs)
    assert "_part1(" in source and "#define" not in source
    model = compile_model(eqs, backend="c")
    x, *_ = _random_batch(model, 20, np.random.default_rng(5))
    np.testing.assert_allclose(model.f(x), reference.f(x), rtol=1e-13, atol=1e-14)
    np.testing.assert_allclose(model.jac_x(x), reference.jac_x(x), rtol=1e-13, atol=1e-14)


# -- algebraic loops ----------------------------------------------------------------------

@pytest.mark.parametrize("backend", _backends())
def test_scalar_loop_solved_to_residual(backend):
    model = compile_model(loop_model(), backend=backend)
    rng = np.random.default_rng(6)
    x = rng.uniform(-2, 2, size=(50, 2))
    u = rng.uniform(-0.5, 0.5, size=(50, 1))
    z = model.solve_algebraic(x, u)[:, 0]
    # residual computed independently in numpy
    assert np.max(np.abs(z - np.cos(x[:, 0] * z) - u[:, 0])) < 1e-12
    # f uses the solved z:  dx1/dt = -a z x0 + sin(t), a = 2
    np.testing.assert_allclose(model.f(x, u, t=0.3)[:, 1], -2.0 * z * x[:, 0] + np.sin(0.3),
                               rtol=1e-12, atol=1e-14)


@pytest.mark.parametrize("backend", _backends())
def test_two_unknown_loop_and_total_jacobian(backend):
    model = compile_model(loop2_model(), backend=backend)
    rng = np.random.default_rng(7)
    x = rng.uniform(-1, 1, size=(20, 2))
    z = model.solve_algebraic(x)
    np.testing.assert_allclose(z[:, 0] + 0.1 * z[:, 1]**3, x[:, 0], atol=1e-12)
    np.testing.assert_allclose(z[:, 1] - 0.5 * np.sin(z[:, 0]), x[:, 1], atol=1e-12)
    # total derivative df/dx by central differences (implicit function theorem reference)
    J = model.jac_x(x)
    eps = 1e-6
    for j in range(2):
        dx = np.zeros(2)
        dx[j] = eps
        fd = (model.f(x + dx) - model.f(x - dx)) / (2 * eps)
        np.testing.assert_allclose(J[:, :, j], fd, rtol=1e-6, atol=1e-8)


@pytest.mark.parametrize("backend", _backends())
def test_a_loop_whose_residual_subtracts_absolute_levels_is_solved_to_its_rounding_floor(backend):
    """Two blocks at 296.15 K and a temperature step d of 1e-6 K across a resistance R and a
    one-way law e = b max(f, 0) of slope b/R = 3389 (graph location's probe of a heater pair with a
    direction-dependent friction fitted at its link): the residual, which subtracts the two levels,
    is known to about 1e-10, and the Newton steps stay near 2e-14, above the absolute tolerance; the
    loop was "not solved" in 50 iterations.  Converged at the floor, f is the analytic flow."""
    q1, q2, d, e = R("q_C1"), R("q_C2"), R("d_link"), R("e_law")     # the blocks' heat, 2 J/K each
    b, res = 1.69441411e6, 500.0
    f = (d - e - q2 / 2 + q1 / 2) / res
    eqs = StateEquations(name="floor", t=R("t"), states=(q1, q2), inputs=(d,), params=(), outputs=(),
                         f=(-f, f), h=(), algebraic=(e,), residuals=(e - b * sp.Max(0, f),))
    model = compile_model(eqs, backend=backend)
    x = np.full((2, 2), 2 * 296.15)
    u = np.array([[1e-6], [1e-3]])
    # to the flow's own rounding floor: one ulp of 296 K over R
    np.testing.assert_allclose(model.f(x, u)[:, 1], u[:, 0] / (res + b), rtol=1e-6, atol=np.spacing(296.15) / res)


@pytest.mark.parametrize("backend", _backends())
def test_unsolvable_loop_names_the_unknown(backend):
    t, x, zbad = R("t"), R("x"), R("zbad")
    eqs = StateEquations(name="bad", t=t, states=(x,), inputs=(), params=(), outputs=(),
                         f=(zbad,), h=(), algebraic=(zbad,), residuals=(zbad**2 + 1 + x**2,))
    model = compile_model(eqs, backend=backend)
    with pytest.raises(SimulationError, match="zbad"):
        model.f([0.5])


@needs_cc
def test_threaded_sample_loop_reports_a_failed_loop_as_one_call(monkeypatch):
    """A Newton failure in one thread's rows: the batch is run again in one call, so the error
    names the batch's rows and time as it would without threads."""
    from bondgraph.numerics import evaluate_samples

    t, x, z = R("t"), R("x"), R("zhard")
    # z^3 + z = x has one real root for every x; the loop fails where x is NaN (rows 3, 4)
    eqs = StateEquations(name="hard", t=t, states=(x,), inputs=(), params=(), outputs=(),
                         f=(-z,), h=(), algebraic=(z,), residuals=(z**3 + z - x,))
    model = compile_model(eqs, backend="c")
    times = np.linspace(0.0, 1.0, 11)
    messages = []
    for threads in ("1", "2"):
        monkeypatch.setenv("BONDCOSIM_THREADS", threads)
        monkeypatch.setattr(evaluate_samples, "_THREAD_WORK", 0)
        x0 = np.array([[1.0], [2.0], [0.5], [np.nan], [np.nan]])
        d0 = np.zeros((5, 0))
        with pytest.raises(SimulationError, match="hard") as info:
            model.rk4_samples(times, np.zeros((11, 0)), np.full(10, 2), x0, d0, np.zeros((1, 0)))
        messages.append(str(info.value))
    assert messages[0] == messages[1] and "row(s) 3, 4" in messages[0]


@needs_cc
def test_backends_take_the_same_newton_path():
    eqs = loop_model()
    mc, mn = compile_model(eqs, backend="c"), compile_model(eqs, backend="numpy")
    x = np.random.default_rng(8).uniform(-3, 3, size=(30, 2))
    np.testing.assert_allclose(mc.solve_algebraic(x, z0=[0.0]), mn.solve_algebraic(x, z0=[0.0]),
                               rtol=1e-13, atol=1e-15)


# -- errors -------------------------------------------------------------------------------

@pytest.mark.parametrize("backend", _backends())
def test_bad_arguments_raise_named_errors(backend):
    model = compile_model(kitchen_sink(), backend=backend)
    with pytest.raises(ParameterError, match="unknown parameter 'mass'.*a, b, c") as info:
        model.f(np.zeros(3), p={"mass": 1.0})
    assert info.value.name == "mass"
    with pytest.raises(ValueError, match=r"x: expected shape \(3,\).*found \(4,\)"):
        model.f(np.zeros(4))
    with pytest.raises(ValueError, match=r"u: expected shape \(2,\) or \(5, 2\).*found \(5, 3\)"):
        model.f(np.zeros((5, 3)), np.zeros((5, 3)))
    with pytest.raises(ValueError, match=r"p: expected.*found \(2,\)"):
        model.f(np.zeros(3), p=np.ones(2))
    with pytest.raises(ValueError, match="backend must be one of"):
        compile_model(kitchen_sink(), backend="fortran")


def test_undeclared_symbol_is_named():
    t, x, k = R("t"), R("x"), R("k")
    eqs = StateEquations(name="undeclared", t=t, states=(x,), inputs=(), params=(), outputs=(),
                         f=(-k * x,), h=())
    with pytest.raises(ExpressionError, match=r"f\[x\] uses k") as info:
        compile_model(eqs, backend="numpy")
    assert info.value.unknown == ["k"]


@needs_cc
def test_compiler_errors_carry_output_and_cache_is_reused(tmp_path):
    with pytest.raises(CompilationError) as info:
        c_build.compile_source("this is not C;\n")
    assert "error" in info.value.output
    src = "double bc_probe(double a) { return 2.0 * a; }\n"
    first = c_build.compile_source(src)
    mtime = first.stat().st_mtime_ns
    second = c_build.compile_source(src)
    assert first == second and second.stat().st_mtime_ns == mtime
    assert first.parent == c_build.cache_dir()


def test_equations_key_is_the_same_in_any_process_and_tells_equations_apart():
    """The lookup key of shipped libraries: the same for an equal but separately derived model, in
    a process with another string-hash seed, and different when one constant or one symbol's
    assumptions change."""
    import os
    import subprocess
    import sys

    from plants import library

    eqs = library.build("pam").equations()
    key = c_build.equations_key(eqs, "main")
    assert key == c_build.equations_key(library.build("pam").equations(), "main")
    assert key != c_build.equations_key(eqs, "jacobian")
    code = ("from plants import library; from bondgraph.numerics import c_build; "
            "print(c_build.equations_key(library.build('pam').equations(), 'main'))")
    for seed in ("0", "12345"):
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                             env={**os.environ, "PYTHONHASHSEED": seed})
        assert out.stdout.strip() == key
    from dataclasses import replace

    sink = kitchen_sink()
    changed = replace(sink, f=(sink.f[0] + sp.Rational(1, 3),) + tuple(sink.f[1:]))
    x = sink.states[0]
    unreal = replace(sink, f=tuple(e.xreplace({x: sp.Symbol(x.name)}) for e in sink.f))
    keys = {c_build.equations_key(e, "main") for e in (sink, changed, unreal)}
    assert len(keys) == 3
