"""SCAP: conflicts named by element and bond, derivative causality, loops, sign conventions."""
import numpy as np
import pytest
import sympy as sp
from hypothesis import given, strategies as st

from bondgraph import BondGraph, C, CausalityError, DerivationError, I, One, R, Se, Sf, TF, Zero
from plants import library


def test_two_effort_sources_on_a_zero_junction_is_a_conflict():
    g = BondGraph("conflict")
    for e in (Se("V1"), Se("V2"), Zero("node"), R("load", 1.0)):
        g.add(e)
    g.connect("V1", "node", name="a")
    g.connect("V2", "node", name="b")
    g.connect("node", "load", name="c")
    with pytest.raises(CausalityError) as info:
        g.equations()
    (conflict,) = info.value.conflicts
    assert set(conflict.elements) == {"V2", "node"}
    assert conflict.bonds == ("b",)
    assert "V2" in str(info.value) and "node" in str(info.value) and "effort" in str(info.value)


def test_every_conflict_is_reported():
    """Three independent conflicts in one graph: all three are named."""
    g = BondGraph("three")
    for k in range(3):
        for e in (Sf(f"Q{k}a"), Sf(f"Q{k}b"), One(f"j{k}"), C(f"c{k}", 1.0)):
            g.add(e)
        g.connect(f"Q{k}a", f"j{k}")
        g.connect(f"Q{k}b", f"j{k}")
        g.connect(f"j{k}", f"c{k}")
    with pytest.raises(CausalityError) as info:
        g.equations()
    assert sorted(c.elements for c in info.value.conflicts) == [("Q0b", "j0"), ("Q1b", "j1"), ("Q2b", "j2")]
    assert "3 causal conflicts" in str(info.value)


def test_source_against_source_across_a_bond():
    g = BondGraph("face_off")
    g.add(Se("E"))
    g.add(Se("E2"))
    g.connect("E", "E2", name="direct")
    with pytest.raises(CausalityError) as info:
        g.equations()
    assert "direct" in str(info.value)


def test_transformer_between_two_effort_sources_conflicts():
    g = BondGraph("tf_conflict")
    for e in (Se("a"), TF("n", 2.0), Se("b")):
        g.add(e)
    g.connect("a", "n")
    g.connect("n", "b")
    with pytest.raises(CausalityError, match="n"):
        g.equations()


def test_flow_source_on_inertia_needs_input_derivative():
    g = BondGraph("sf_mass")
    g.add(Sf("v"))
    g.add(I("m", 1.0))
    g.connect("v", "m")
    with pytest.raises(DerivationError) as info:
        g.equations()
    assert info.value.element == "m" and "v" in str(info.value)


def test_causality_assignment_records_strokes():
    g = library.build("mass-spring-damper")
    ca = g.causality()
    bonds = list(g.bonds.values())
    # Se sets the effort on its bond; the I receives effort (flow out), the C sets effort.
    by_head = {b.head.element: b for b in bonds}
    assert ca.effort_by[bonds[0].name] == "tail"          # F -> junction
    assert ca.effort_by[by_head["m"].name] == "tail"      # junction sets the effort on I
    assert ca.effort_by[by_head["k"].name] == "head"      # C sets the effort
    assert ca.stroke_end(by_head["m"]) == "head"
    assert ca.derivative == [] and ca.arbitrary == []


def _oriented_msd(flips):
    """Mass-spring-damper with each bond drawn in either direction."""
    g = BondGraph("msd_flipped")
    for e in (Se("F"), One("j"), I("m", 2.0), R("b", 0.5), C("k", stiffness=3.0)):
        g.add(e)
    pairs = [("F", "j"), ("j", "m"), ("j", "b"), ("j", "k")]
    for flip, (a, b) in zip(flips, pairs):
        g.connect(*((b, a) if flip else (a, b)))
    g.add_output("x", "q_k")
    g.add_output("v", "f_m")
    return g


def _transfer_function(eqs, u, y):
    x = sp.Matrix(eqs.states)
    A, B = sp.Matrix(eqs.f).jacobian(x), sp.Matrix(eqs.f).jacobian([u])
    C = sp.Matrix([eqs.h[eqs.outputs.index(y)]]).jacobian(x)
    s = sp.Symbol("s")
    return sp.simplify((C * (s * sp.eye(len(x)) - A).LUsolve(B))[0])


@given(st.lists(st.booleans(), min_size=4, max_size=4))
def test_bond_orientation_is_a_sign_convention(flips):
    """Drawing a half-arrow the other way only flips signs: the transfer
    function F -> v keeps its poles and changes sign exactly when the bond
    of the source or of the mass is reversed (the source then pushes the
    other way; the mass's natural flow ``f_m`` is measured the other way)."""
    F = sp.Symbol("F", real=True)
    reference = _transfer_function(_oriented_msd([False] * 4).equations(), F, "v")
    flipped = _transfer_function(_oriented_msd(flips).equations(), F, "v")
    sign = (-1) ** (flips[0] + flips[1])
    assert sp.simplify(flipped - sign * reference) == 0


def _all_bond_outputs(g):
    for name in list(g.bonds):
        g.add_output(f"E_{name}", f"e_{name}")
        g.add_output(f"F_{name}", f"f_{name}")
    return g


@pytest.mark.parametrize("model", ["mass-spring-damper", "dc-motor", "coupled-tanks", "resistor-loop",
                                   "geared-inertias", "chain"])
def test_junctions_conserve_power(model, rng):
    """sum(sign * e * f) = 0 at every junction, at random states and inputs."""
    g = _all_bond_outputs(library.build(model))
    eqs = g.equations()
    values = {p: eqs.param_values[p.name] for p in eqs.params}
    for _ in range(3):
        point = dict(values)
        point.update({s: float(v) for s, v in zip(eqs.states, rng.uniform(0.001, 0.01, len(eqs.states)))})
        point.update({u: float(v) for u, v in zip(eqs.inputs, rng.uniform(-1, 1, len(eqs.inputs)))})
        out = {n: float(h.subs(point)) for n, h in zip(eqs.outputs, eqs.h) if n[:2] in ("E_", "F_")}
        for name, element in g.elements.items():
            if element.ports is not None:
                continue
            total = 0.0
            for bond, end in g.bonds_of(name):
                sign = 1.0 if end == "head" else -1.0
                total += sign * out[f"E_{bond.name}"] * out[f"F_{bond.name}"]
            scale = max(abs(out[f"E_{b.name}"] * out[f"F_{b.name}"]) for b, _ in g.bonds_of(name)) + 1e-300
            assert abs(total) <= 1e-9 * scale, (name, total)
    assert np.isfinite(total)
