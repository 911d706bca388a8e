"""Ordered causal assignments (bondgraph/assignments.py): the readable form of the equations.

Reference: the flat (fully substituted) ``f``, ``h`` and ``held_update`` of the same derivation,
which the block-diagram twins check (tests/test_pam_compare.py, tests/test_exoskeleton.py).
Substituting the assignments into the short forms must give them back, symbolically where
cheap and at random points always.
"""
from __future__ import annotations

import json

import numpy as np
import pytest
import sympy as sp

from bondcosim.cli import main
from plants import library
from bondgraph.assignments import substitute
from bondgraph.numerics.evaluate import compile_model
from bondgraph.io_json import dumps, graph_from_dict

MODELS = library.names()


def _point(eqs, rng):
    """Random values for every symbol: pressures 1.2-6 bar, voltages 0-10 V, small angles, else U(0.1, 1)."""
    values = {}
    for s in (eqs.t, eqs.step, *eqs.states, *eqs.inputs, *eqs.held, *eqs.algebraic):
        name = s.name
        if name.startswith("P_"):
            values[s] = rng.uniform(1.2e5, 6e5)
        elif name.startswith("u") and eqs.name.startswith("pam"):
            values[s] = rng.uniform(0, 10)
        elif name in ("h_step",):
            values[s] = 2.5e-4
        else:
            values[s] = rng.uniform(0.1, 1) * (0.3 if name == "q_psi" else 1.0)   # positive: tank levels
    values.update({p: eqs.param_values[p.name] for p in eqs.params})
    return values


@pytest.mark.parametrize("name", MODELS)
def test_assignments_substituted_give_the_flat_equations(name):
    eqs = library.build(name).equations()
    rng = np.random.default_rng(14)
    pairs = [*zip(eqs.f_short, eqs.f), *zip(eqs.h_short, eqs.h), *zip(eqs.held_update_short, eqs.held_update)]
    defined = set()
    for symbol, body in eqs.assignments:   # evaluation order: each uses only earlier ones
        assert not (body.free_symbols & {s for s, _ in eqs.assignments}) - defined, symbol
        defined.add(symbol)
    for short, flat in pairs:
        back = substitute(eqs.assignments, short)
        assert not (back.free_symbols & defined)
        for _ in range(5):
            point = _point(eqs, rng)
            a, b = float(back.xreplace(point)), float(flat.xreplace(point))
            assert a == pytest.approx(b, rel=1e-9, abs=1e-12), (name, short)


def test_linear_model_assignments_are_symbolically_exact():
    eqs = library.build("dc-motor").equations()
    for short, flat in zip(eqs.f_short, eqs.f):
        assert sp.expand(substitute(eqs.assignments, short) - flat) == 0


def test_pam_names_its_intermediates_and_stays_short():
    eqs = library.build("pam").equations()
    names = eqs.assignment_names()
    for i in (1, 2):
        for local in (f"valve{i}.alpha", f"valve{i}.m_in", f"valve{i}.net", f"f_valve{i}",
                      f"muscle{i}.l", f"muscle{i}.V", f"muscle{i}.F"):
            assert local in names
    assert {"friction.w", "friction.F_c"} <= set(names)
    # every state equation fits on a line; the flat ones are thousands of characters
    assert max(len(str(f)) for f in eqs.f_short) < 120
    assert min(len(str(f)) for f in eqs.f[:2]) > 2000
    text = eqs.pretty()
    assert "assignments, in evaluation order:" in text and "valve1.alpha" in text
    assert "valve1.alpha" not in eqs.pretty(flat=True)
    assert r"\mathrm{valve1}.\alpha" in eqs.latex() and "mathrm" not in eqs.latex(flat=True)
    assert eqs._repr_latex_().startswith("$\\begin{aligned}")


def test_pam_compiled_from_assignments_matches_the_flat_numpy_evaluator():
    """C code (built from the assignments) vs numpy (lambdified flat f), random states."""
    from bondgraph.numerics.c_build import find_compiler
    if find_compiler() is None:
        pytest.skip("no C compiler")
    eqs = library.build("pam").equations()
    rng = np.random.default_rng(5)
    x = np.column_stack([rng.uniform(1.2e5, 6e5, 50), rng.uniform(1.2e5, 6e5, 50),
                         rng.uniform(-1e-3, 1e-3, 50), rng.uniform(-0.3, 0.3, 50)])
    u = rng.uniform(0, 10, (50, 2))
    d = rng.uniform(-0.05, 0.05, (50, 1))
    c, n = compile_model(eqs, backend="c"), compile_model(eqs, backend="numpy")
    np.testing.assert_allclose(c.f(x, u, d=d), n.f(x, u, d=d), rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(c.h(x, u, d=d), n.h(x, u, d=d), rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(c.update_held(x, u, d=d, step=2.5e-4), n.update_held(x, u, d=d, step=2.5e-4),
                               rtol=1e-10, atol=1e-12)


def test_locals_survive_json_and_name_clashes_are_refused():
    g = library.build("pam")
    again = graph_from_dict(json.loads(dumps(g)))
    assert again.elements["valve1"].locals == g.elements["valve1"].locals
    assert again.equations().assignment_names() == g.equations().assignment_names()
    from bondgraph import BondGraph, One, I, MSe
    from bondgraph.errors import GraphError
    h = BondGraph("clash")
    h.add(MSe("F", "2*m", locals={"m": "1"}, domain="translation"))
    h.add(One("v"))
    h.add(I("m", 1.0, domain="translation"))
    h.connect("F", "v")
    h.connect("v", "m")
    with pytest.raises(GraphError, match="local 'm' shadows"):
        h.equations()


def test_cli_equations_default_flat_and_json(capsys):
    assert main(["equations", "pam-locked"]) == 0
    out = capsys.readouterr().out
    assert "assignments, in evaluation order:" in out and "valve1.alpha" in out
    assert max(len(line) for line in out.splitlines() if line.lstrip().startswith("dP_")) < 200
    assert main(["equations", "pam-locked", "--flat"]) == 0
    assert "valve1.alpha" not in capsys.readouterr().out
    assert main(["equations", "mass-spring-damper", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["assignments"] == [{"name": "f_m", "expression": "p_m/m"}]
    assert data["f_short"] == ["F - b*f_m - k*q_k", "f_m"]
