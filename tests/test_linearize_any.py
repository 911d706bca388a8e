"""Linearisation of every built-in model, switched laws included (bondgraph/linearization.py).

References: the compiled right-hand side (bondgraph.numerics.evaluate, C backend when a compiler is there)
differentiated by finite differences here, independently of the linearisation's own code; and,
at a point where the PAM laws are differentiable, the symbolic Jacobian against the numerical one.
"""
from __future__ import annotations

import json

import numpy as np
import pytest

from bondcosim.cli import main
from plants import library
from bondgraph.errors import ParameterError
from bondgraph.numerics.evaluate import compile_model


@pytest.mark.parametrize("name", library.names())
def test_equations_json_linearises_every_listed_model(name, capsys):
    assert main(["equations", name, "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    for key in ("A", "B", "C", "D"):
        assert np.all(np.isfinite(np.array(data[key], dtype=float).reshape(-1))), key
    how = data["linearisation"]["derivatives"]
    assert set(how) == set(data["states"]) | set(data["inputs"])
    assert all(v == "symbolic" or v.startswith("one-sided numerical") for v in how.values())


def _fd(model, x0, u0, d0, *, central: bool, rel: float):
    """Jacobians of (f, h) by finite differences of the compiled model."""
    def F(x, u):
        return np.concatenate([model.f(x, u, d=d0), model.h(x, u, d=d0)])
    cols = []
    for vec, k in [(0, j) for j in range(len(x0))] + [(1, j) for j in range(len(u0))]:
        base = (x0, u0)[vec]
        h = rel * max(1.0, abs(base[k]))
        e = np.zeros_like(base)
        e[k] = h
        plus = F(x0 + e, u0) if vec == 0 else F(x0, u0 + e)
        if central:
            minus = F(x0 - e, u0) if vec == 0 else F(x0, u0 - e)
            cols.append((plus - minus) / (2 * h))
        else:   # right-sided, second order, with a step 20x larger than the linearisation's
            plus2 = F(x0 + 2 * e, u0) if vec == 0 else F(x0, u0 + 2 * e)
            cols.append((-3 * F(x0, u0) + 4 * plus - plus2) / (2 * h))
    return np.array(cols).T


def _abcd(lin):
    return np.block([[lin.A, lin.B], [lin.C, lin.D]])


def test_pam_at_its_default_point_is_one_sided_where_the_valves_switch():
    eqs = library.build("pam").equations()
    lin = eqs.linearize()
    how = lin.derivatives
    # P_i = P_out and u_i = 0: sign(P_i - P_out), Max(0, u_i) and Abs(net) sit on their kinks
    assert {k for k, v in how.items() if v != "symbolic"} == {"P_1", "P_2", "u1", "u2"}
    assert any("sign(P_1 - P_out)" in k for k in lin.kinks) and any("Max(0, u1)" in k for k in lin.kinks)
    # venting at zero pressure difference: m_out ~ sqrt(P - P_out), an unbounded slope -> secant, said so
    assert "secant over 101" in how["P_1"] and "unbounded" in how["P_1"]
    assert how["u1"].startswith("one-sided numerical (right")
    model = compile_model(eqs)
    x0 = np.array([lin.operating_point[s] for s in eqs.state_names])
    u0 = np.array([lin.operating_point[s] for s in eqs.input_names])
    d0 = np.array([eqs.held_initial[s] for s in eqs.held_names])
    ref = _fd(model, x0, u0, d0, central=False, rel=1.2e-4)
    got = _abcd(lin)
    scale = np.maximum(np.abs(ref).max(axis=0), 1e-12)
    cols = [2, 3, 4, 5]   # p_J, q_psi (symbolic), u1, u2 (one-sided)
    np.testing.assert_allclose(got[:, cols] / scale[cols], ref[:, cols] / scale[cols], atol=2e-4)
    # the secant over 1e-3 * P_out = 101.3 Pa, from the compiled model
    dP = 1e-3 * x0[0]
    e = np.array([dP, 0, 0, 0])
    secant = (model.f(x0 + e, u0, d=d0) - model.f(x0, u0, d=d0)) / dP
    np.testing.assert_allclose(lin.A[:, 0], secant, rtol=1e-6, atol=1e-12)
    assert lin.A[0, 0] < 0 and lin.B[0, 0] > 0 and lin.B[0, 1] == 0


def test_pam_where_differentiable_symbolic_equals_numerical_and_finite_differences():
    eqs = library.build("pam").equations()
    point = {"P_1": 3.1e5, "P_2": 2.4e5, "p_J": 2e-5, "q_psi": 0.07, "u1": 6.2, "u2": 3.7}
    lin = eqs.linearize(point)
    assert set(lin.derivatives.values()) == {"symbolic"} and lin.kinks == ()
    num = eqs.linearize(point, method="numerical")
    assert all(v.startswith("one-sided") for v in num.derivatives.values())
    scale = np.maximum(np.abs(_abcd(lin)).max(axis=0), 1e-12)
    np.testing.assert_allclose(_abcd(num) / scale, _abcd(lin) / scale, atol=1e-5)
    model = compile_model(eqs)
    x0 = np.array([point[s] for s in eqs.state_names])
    u0 = np.array([point[s] for s in eqs.input_names])
    d0 = np.array([eqs.held_initial[s] for s in eqs.held_names])
    ref = _fd(model, x0, u0, d0, central=True, rel=1e-6)
    np.testing.assert_allclose(_abcd(lin) / scale, ref / scale, atol=1e-5)


def test_coupled_tanks_symbolic_matches_torricelli():
    """Q12 = a12 sqrt(2 g |h1 - h2|) sign(h1 - h2): d Q12 / d V1 = a12 g rho/(A1 rho sqrt(2 g dh)) ..."""
    eqs = library.build("coupled-tanks").equations()
    lin = eqs.linearize()
    assert set(lin.derivatives.values()) == {"symbolic"}
    model = compile_model(eqs)
    x0 = np.array([lin.operating_point[s] for s in eqs.state_names])
    u0 = np.array([lin.operating_point[s] for s in eqs.input_names])
    ref = _fd(model, x0, u0, np.zeros(0), central=True, rel=1e-7)
    np.testing.assert_allclose(_abcd(lin), ref, rtol=1e-5, atol=1e-10)


def test_cli_at_sets_the_point_and_bad_uses_are_named(capsys):
    assert main(["equations", "pam-locked", "--json", "--at", "P_1=3e5", "--at", "u1=6.2"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["linearisation"]["operating_point"]["P_1"] == 3e5
    assert data["linearisation"]["derivatives"]["u1"] == "symbolic"
    assert main(["equations", "pam-locked", "--at", "P_1=3e5"]) == 1
    assert "--at" in capsys.readouterr().err
    assert main(["equations", "pam-locked", "--json", "--at", "nope=1"]) == 1
    assert "'nope'" in capsys.readouterr().err
    assert main(["equations", "pam-locked", "--json", "--at", "P_1=high"]) == 1
    assert "not a number" in capsys.readouterr().err


def test_unknown_method_is_refused():
    with pytest.raises(ParameterError, match="method must be one of"):
        library.build("rlc").equations().linearize(method="guess")
