"""The graph-editing API (copy, with_params, insert, insert_on_bond, replace, remove): each edit
gives a new graph whose state equations equal the ones derived by hand for the edited circuit,
and leaves the original graph and its equations untouched."""
from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

from bondgraph import (C, GraphError, I, One, Param, ParameterError, PortError, R, Se, TF, UnknownNameError, Zero,
                       BondGraph)
from bondgraph.symbols import sym
from plants import library

F, m, c, b, p, q = (sym(n) for n in ("F", "m", "c", "b", "p_m", "q_c"))


def msd() -> BondGraph:
    """Force F on mass m, spring of compliance c, damper b, all on one 1-junction ``v``:
    dp/dt = F - b p/m - q/c, dq/dt = p/m."""
    g = BondGraph("msd")
    for e in (Se("F"), One("v"), I("m", 2.0), C("c", 0.5), R("b", 0.4)):
        g.add(e)
    g.connect("v", "m", name="to_m")
    g.connect("v", "c", name="to_c")
    g.connect("v", "b", name="to_b")
    g.connect("F", "v", name="from_F")
    return g


def assert_equations(graph, states, f):
    eqs = graph.equations()
    assert [str(s) for s in eqs.states] == states
    assert len(eqs.f) == len(f)
    for got, want in zip(eqs.f, f):
        assert sp.simplify(got - want) == 0, (got, want)


@pytest.fixture
def graph():
    g = msd()
    assert_equations(g, ["p_m", "q_c"], [F - b * p / m - q / c, p / m])
    return g


def unchanged(g):
    assert list(g.elements) == ["F", "v", "m", "c", "b"]
    assert list(g.bonds) == ["to_m", "to_c", "to_b", "from_F"]
    assert g.parameters()["b"].value == 0.4
    assert_equations(g, ["p_m", "q_c"], [F - b * p / m - q / c, p / m])


def test_copy_is_independent(graph):
    twin = graph.copy(name="twin")
    twin.add(R("extra", 1.0))
    assert twin.name == "twin" and "extra" not in graph.elements
    unchanged(graph)


def test_with_params_changes_values_not_equations(graph):
    stiff = graph.with_params({"c": 0.125}, b=1.5)
    assert stiff.equations().param_values == {"m": 2.0, "c": 0.125, "b": 1.5}
    # A = [[-b/m, -1/c], [1/m, 0]] at the new values
    np.testing.assert_allclose(np.asarray(stiff.equations().linearize().A, float),
                               [[-1.5 / 2.0, -1 / 0.125], [1 / 2.0, 0.0]], rtol=1e-12)
    unchanged(graph)


def test_with_params_reaches_every_copy_of_a_shared_parameter():
    pam = library.build("pam")
    name, param = next(iter(pam.parameters().items()))
    new = pam.with_params({name: param.value * 1.5})
    assert new.parameters()[name].value == pytest.approx(param.value * 1.5)
    assert new.equations().param_values[name] == pytest.approx(param.value * 1.5)
    assert pam.parameters()[name].value == param.value


def test_with_params_rejects_unknown_names_and_bad_values(graph):
    with pytest.raises(UnknownNameError, match=r"unknown parameter 'k' of model 'msd'; known parameters are m, c, b"):
        graph.with_params(k=1.0)
    with pytest.raises(ParameterError, match="'m'"):
        graph.with_params(m=-1.0)
    unchanged(graph)


def test_insert_a_second_damper_on_the_junction(graph):
    r2 = sym("b2")
    assert_equations(graph.insert(R("b2", 0.1), at="v"), ["p_m", "q_c"],
                     [F - (b + r2) * p / m - q / c, p / m])
    unchanged(graph)


def test_insert_a_source_points_its_bond_out_of_it(graph):
    new = graph.insert(Se("G"), at="v", bond="from_G")
    assert new.bonds["from_G"].tail.element == "G"
    assert_equations(new, ["p_m", "q_c"], [F + sym("G") - b * p / m - q / c, p / m])


def test_insert_on_bond_a_zero_junction_puts_a_leak_across_the_spring(graph):
    """0-junction in the spring's bond, R:r on it: the spring's effort q/c drives q/(c r)
    through r, so dq/dt = p/m - q/(c r)."""
    leaky = graph.insert_on_bond("to_c", Zero("z")).insert(R("r", 3.0), at="z")
    assert list(leaky.bonds)[:3] == ["to_m", "to_c", "to_c_z"]
    assert_equations(leaky, ["p_m", "q_c"], [F - b * p / m - q / c, p / m - q / (c * sym("r"))])
    unchanged(graph)


def test_insert_on_bond_a_one_junction_puts_a_damper_in_series(graph):
    """1-junction in the damper's bond, R:b2 on it: same flow p/m, efforts add."""
    series = graph.insert_on_bond("to_b", One("w")).insert(R("b2", 0.1), at="w")
    assert_equations(series, ["p_m", "q_c"], [F - (b + sym("b2")) * p / m - q / c, p / m])


def test_insert_on_bond_a_transformer_scales_the_force(graph):
    """TF:n in the source's bond: e1 = n e2, so the junction sees F/n."""
    geared = graph.insert_on_bond("from_F", TF("n", 2.0))
    assert_equations(geared, ["p_m", "q_c"], [F / sym("n") - b * p / m - q / c, p / m])
    unchanged(graph)


def test_replace_keeps_the_bonds_and_follows_a_new_name(graph):
    """The damper becomes a second spring c2: a new state q_c2 with dq_c2/dt = p/m."""
    springs = graph.replace("b", C("c2", 0.25))
    assert springs.bonds["to_b"].head.element == "c2" and list(springs.elements)[-1] == "c2"
    q2, c2 = sym("q_c2"), sym("c2")
    assert_equations(springs, ["p_m", "q_c", "q_c2"], [F - q / c - q2 / c2, p / m, p / m])
    unchanged(graph)


def test_remove_an_element_or_a_bond(graph):
    assert_equations(graph.remove("b"), ["p_m", "q_c"], [F - q / c, p / m])
    without_bond = graph.remove("to_b")
    assert "to_b" not in without_bond.bonds and "b" in without_bond.elements
    with pytest.raises(GraphError, match=r"R 'b': its port has no bond"):
        without_bond.equations()
    unchanged(graph)


def test_editing_errors_name_the_culprit(graph):
    with pytest.raises(GraphError, match=r"I 'm' is not a junction; the junctions are v"):
        graph.insert(R("b2", 0.1), at="m")
    with pytest.raises(UnknownNameError, match=r"unknown element 'nope' of model 'msd'; known elements are F, v"):
        graph.remove("nope")
    with pytest.raises(UnknownNameError, match=r"unknown bond 'nope'.*to_m, to_c, to_b, from_F"):
        graph.insert_on_bond("nope", One("w"))
    with pytest.raises(PortError, match=r"R 'v' cannot replace 1-junction 'v': ports \(one port\) instead of \(any number: a junction\)"):
        graph.replace("v", R("v", 1.0))
    with pytest.raises(PortError, match=r"insert\(\) bonds one-port elements; TF 'n'"):
        graph.insert(TF("n", 2.0), at="v")
    with pytest.raises(PortError, match=r"insert_on_bond\(\) takes a junction or a two-port; R 'r'"):
        graph.insert_on_bond("to_b", R("r", 1.0))
    unchanged(graph)


def test_declare_adds_graph_wide_parameters(graph):
    from bondgraph import DuplicateNameError
    loaded = graph.insert(R("load", effort="F0"), at="v").declare(Param("F0", 0.3, "N"))
    assert loaded.parameters()["F0"].value == 0.3
    assert_equations(loaded, ["p_m", "q_c"], [F - sym("F0") - b * p / m - q / c, p / m])
    with pytest.raises(DuplicateNameError, match="F0"):
        loaded.declare(Param("F0", 1.0))
    unchanged(graph)


def test_insert_a_junction_and_an_element_with_a_named_port(graph):
    """A 1-junction hung on v carries a damper b2 (same flow); an equation element with one
    port m adds its effort -k1 * (its flow)."""
    from bondgraph import EquationElement
    branch = graph.insert(One("w"), at="v", bond="to_w").insert(R("b2", 0.1), at="w")
    assert branch.bonds["to_w"].tail.element == "v" and branch.bonds["to_w"].head.element == "w"
    assert_equations(branch, ["p_m", "q_c"], [F - (b + sym("b2")) * p / m - q / c, p / m])
    eq = graph.insert(EquationElement("drag", ports={"m": "in"}, outputs={"e_m": "2*f_m"}), at="v", bond="to_drag")
    assert eq.bonds["to_drag"].head.port == "m"
    assert_equations(eq, ["p_m", "q_c"], [F - (b + 2) * p / m - q / c, p / m])
    unchanged(graph)


def test_with_law_rewrites_a_storage_law_in_sympy(graph):
    k3 = sym("k3")
    hard = graph.with_law("c", lambda old, q: old + sp.Symbol("k3") * q ** 3)
    hard = hard.declare(Param("k3", 2.0))
    assert hard.parameters()["c"].value == 0.5            # the linear value is still used: kept
    assert_equations(hard, ["p_m", "q_c"], [F - b * p / m - q / c - k3 * q ** 3, p / m])
    cubic = graph.with_law("c", "k3*q**3").declare(Param("k3", 2.0))
    assert "c" not in cubic.parameters()                   # no longer used: dropped
    assert_equations(cubic, ["p_m", "q_c"], [F - b * p / m - k3 * q ** 3, p / m])
    twice = cubic.with_law("c", lambda old, q: old.subs(q, 2 * q))   # a law read back and edited again
    assert_equations(twice, ["p_m", "q_c"], [F - b * p / m - 8 * k3 * q ** 3, p / m])
    with pytest.raises(GraphError, match="neither"):
        graph.with_law("b", "q")
    unchanged(graph)


def test_with_output_and_with_element(graph):
    g = graph.copy()
    g.add_output("x", "q_c", unit="m")
    off = g.with_output("x", lambda y: y + sp.Symbol("dx")).declare(Param("dx", 0.1))
    assert off.outputs["x"].unit == "m"
    assert sp.simplify(off.equations().h[0] - (q + sym("dx"))) == 0
    assert g.outputs["x"].expression == "q_c"
    stiff = graph.with_element("c", value=0.25, description="a stiffer spring")
    assert stiff.elements["c"].description == "a stiffer spring" and stiff.parameters()["c"].value == 0.25
    unchanged(graph)


def test_route_input_makes_the_source_read_an_expression_and_own_new_states(graph):
    x, tau = sym("x_lag"), sym("tau")
    sat = graph.route_input("F", "Min(F, 1)").declare()
    assert sat.elements["F"].kind == "MSe" and [d.name for d in sat.inputs()] == ["F"]
    assert_equations(sat, ["p_m", "q_c"], [sp.Min(F, 1) - b * p / m - q / c, p / m])
    lag = graph.route_input("F", "x_lag", states={"x_lag": "(F - x_lag)/tau"}, initial={"x_lag": 0.0},
                            units={"x_lag": "N"})
    lag.add_parameter(Param("tau", 0.1, "s"))
    assert lag.elements["F"].kind == "Eq" and lag.bonds["from_F"].tail.port == "out"
    assert_equations(lag, ["x_lag", "p_m", "q_c"], [(F - x) / tau, x - b * p / m - q / c, p / m])
    with pytest.raises(UnknownNameError, match="input 'G'"):
        graph.route_input("G", "G")
    unchanged(graph)


def test_with_outputs_replaces_the_outputs(graph):
    g = graph.copy()
    g.add_output("x", "q_c", unit="m")
    probes = g.with_outputs({"force": "e_to_c", "speed": ("f_to_m", "m/s")})
    assert list(probes.outputs) == ["force", "speed"] and probes.outputs["speed"].unit == "m/s"
    assert [sp.simplify(h - want) for h, want in zip(probes.equations().h, [q / c, p / m])] == [0, 0]
    assert list(g.outputs) == ["x"]
    unchanged(graph)


def test_route_input_with_states_keeps_a_modulated_sources_own_parameters():
    """A heater's power ``alpha*Q`` (an MSf whose parameter ``alpha`` is its own) seen through a
    lag: the equation element that takes over the source and the lag's state keeps ``alpha``
    (it was dropped, and the lagged graph could not be derived)."""
    from bondgraph import MSf
    g = BondGraph("heater")
    g.add_input("Q", unit="1")
    for e in (MSf("heater", "alpha*Q", params={"alpha": 0.01}, domain="thermal"), Zero("block"),
              C("Cth", 2.0, domain="thermal"), R("Rl", 50.0, domain="thermal")):
        g.add(e)
    for tail, head in (("heater", "block"), ("block", "Cth"), ("block", "Rl")):
        g.connect(tail, head)
    lag = g.route_input("Q", "x_lag", states={"x_lag": "(Q - x_lag)/tau"}, initial={"x_lag": 0.0},
                        units={"x_lag": "1"})
    lag.add_parameter(Param("tau", 20.0, "s"))
    assert lag.elements["heater"].kind == "Eq" and lag.parameters()["alpha"].value == 0.01
    Q, x, alpha, tau, Cth, Rl, q = (sym(n) for n in ("Q", "x_lag", "alpha", "tau", "Cth", "Rl", "q_Cth"))
    assert_equations(lag, ["x_lag", "q_Cth"], [(Q - x) / tau, alpha * x - q / (Cth * Rl)])


def test_sense_output_reads_an_output_through_a_sensor_lag_that_owns_its_state():
    """A mass pushed from rest by a constant force has v = a t (a = F/m); a first-order velocity
    sensor then reads a (t - tau (1 - exp(-t/tau))).  The lag's state belongs to an equation
    element without ports, which saves to JSON (valid against the schema) and loads back."""
    import json
    from pathlib import Path

    import jsonschema
    from bondgraph.io_json import dumps, graph_from_dict
    from bondgraph.numerics import simulate
    g = BondGraph("pushed")
    for e in (Se("F", 2.0), One("v"), I("m", 4.0)):
        g.add(e)
    g.connect("F", "v")
    g.connect("v", "m")
    g.add_output("speed", "p_m/m", unit="m/s")
    y_s, tau = sym("y_s"), sym("tau")
    lag = g.sense_output("speed", {"y_s": lambda y: (y - y_s) / tau}, "y_s", initial={"y_s": 0.0},
                         units={"y_s": "m/s"}).declare(Param("tau", 0.5, "s"))
    assert lag.elements["sensor_speed"].ports == () and not lag.bonds_of("sensor_speed")
    assert lag.outputs["speed"].expression == "y_s" and lag.outputs["speed"].unit == "m/s"
    assert_equations(lag, ["p_m", "y_s"], [F, (p / m - y_s) / tau])
    t = np.linspace(0.0, 3.0, 31)
    got = simulate(lag, (0.0, 3.0), output_interval=0.1)["speed"]
    assert np.allclose(got, 0.5 * (t - 0.5 * (1 - np.exp(-t / 0.5))), atol=1e-6)
    schema = json.loads((Path(__file__).parents[1] / "bondgraph" / "graph.schema.json").read_text())
    jsonschema.validate(json.loads(dumps(lag)), schema)
    again = graph_from_dict(json.loads(dumps(lag)))
    assert_equations(again, ["p_m", "y_s"], [F, (p / m - y_s) / tau])
    with pytest.raises(UnknownNameError, match="output 'x'"):
        g.sense_output("x", {}, "0")
    assert list(g.elements) == ["F", "v", "m"]      # the original graph is untouched
