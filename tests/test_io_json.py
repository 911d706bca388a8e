"""JSON save/load of bond graphs (bondgraph/io_json.py, docs/json-schema.md).

Round trips are checked on the derived equations (``str`` of every f and h,
the symbol tuples, parameter values and every other field of
StateEquations) and on the bytes written; bad files must raise SchemaError
naming the offending entry by JSON path.
"""
import inspect
import json
import math
import re
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bondgraph import (BondGraph, C, CField, ELEMENT_KINDS, EquationElement, GraphError, Guard, GY, I, IField, MGY, MSe,
                       MSf, MTF, One, Param, ParameterError, PneumaticChamber, R, SchemaError, Se, Sf, TF, Zero)
from bondgraph.io_json import ELEMENT_KEYS, dumps, graph_from_dict, graph_to_dict, load, save
from plants.library.chain import mass_spring_chain
from plants.library.textbook import coupled_tanks, dc_motor, mass_spring_damper, resistor_loop

ROOT = Path(__file__).resolve().parents[1]
SCHEMA = json.loads((ROOT / "bondgraph" / "graph.schema.json").read_text(encoding="utf-8"))


# -- graphs using every element kind -------------------------------------------------
def msd_forms():
    """Se as a function of time; I, R and C (stiffness) by value; extra input/parameter/output; operating point."""
    g = BondGraph("msd", description="mass-spring-damper")
    g.add(Se("F", "sin(t)", domain="translation", description="applied force"))
    g.add(One("j"))
    g.add(I("m", 2.0, domain="translation"))
    g.add(R("b", 0.5, domain="translation"))
    g.add(C("k", stiffness=10.0, domain="translation", initial=0.01))
    for e in ("m", "b", "k"):
        g.connect("j", e)
    g.connect("F", "j", name="force")
    g.add_input("unused_u", default=0.25, unit="N", description="declared, not used")
    g.add_parameter(Param("x_ref", 0.1, "m", "reference position"))
    g.add_output("x_err", "q_k - x_ref", unit="m", description="position error")
    g.add_output("v", "f_m", unit="m/s")
    g.operating_point.update({"p_m": 0.0, "q_k": 0.05})
    return g


def law_forms():
    """Sf by number; C by compliance value and by law; I by law; R by effort= and flow= laws."""
    g = BondGraph("laws", description="storage and resistance given as laws")
    g.add(Sf("Q", 1e-3, domain="hydraulic", input="Q_in", unit="m^3/s"))
    g.add(Zero("P"))
    g.add(C("tank", law="q/Ct", params={"Ct": Param("Ct", 2e-3, "m^3/Pa", "tank compliance")},
            domain="hydraulic", state="V", initial=1e-4))
    g.add(One("pipe"))
    g.add(I("L", law="p/Lv", params={"Lv": {"value": 5.0, "unit": "Pa s^2/m^3"}}, domain="hydraulic"))
    g.add(R("valve", effort="Rv*f + a3*f**3", params=[Param("Rv", 40.0, "Pa s/m^3"), Param("a3", 0.1)]))
    g.add(Zero("P2"))
    g.add(C("acc", 1e-3, domain="hydraulic"))
    g.add(R("leak", flow="e/Rl", params={"Rl": 300.0}, domain="hydraulic"))
    g.connect("Q", "P")
    g.connect("P", "tank")
    g.connect("P", "pipe")
    g.connect("pipe", "L")
    g.connect("pipe", "valve")
    g.connect("pipe", "P2")
    g.connect("P2", "acc")
    g.connect("P2", "leak")
    g.add_output("p_tank", "e_tank", unit="Pa")
    return g


def two_ports():
    """MSe with params and an extra input; TF, GY, MTF, MGY; MSf into a 0-junction."""
    g = BondGraph("twoports", description="every two-port kind")
    g.add_input("r", default=0.3, unit="m/s", description="speed reference")
    g.add(MSe("u", "kp*(r - f_m1)", params={"kp": Param("kp", 4.0, "N s/m")}, domain="translation"))
    g.add(One("j1"))
    g.add(I("m1", 1.0))
    g.add(TF("n", 0.5, description="lever"))
    g.add(One("j2"))
    g.add(R("b2", 0.2))
    g.add(GY("km", 0.05, unit="N m/A"))
    g.add(One("j3"))
    g.add(I("m3", 0.1))
    g.add(MTF("mt", "a*cos(p_m3)", params={"a": Param("a", 2.0)}))
    g.add(Zero("z4"))
    g.add(C("c4", 0.2))
    g.add(MSf("w", "0.1*sin(t)"))
    g.add(MGY("mg", "g0 + g1*t", params={"g0": 1.0, "g1": 0.01}, unit="V s"))
    g.add(One("j5"))
    g.add(R("r5", 7.0))
    for tail, head in (("u", "j1"), ("j1", "m1"), ("j1", "n"), ("n", "j2"), ("j2", "b2"), ("j2", "km"),
                       ("km", "j3"), ("j3", "m3"), ("j3", "mt"), ("mt", "z4"), ("z4", "c4"), ("w", "z4"),
                       ("z4", "mg"), ("mg", "j5"), ("j5", "r5")):
        g.connect(tail, head)
    g.add_output("speed", "f_m1", unit="m/s")
    return g


def fields():
    """CField by laws and by energy, IField by laws."""
    g = BondGraph("fields", description="C and I fields")
    g.add(Sf("v_in", 0.1))
    g.add(Zero("z1"))
    g.add(CField("cf", ["a", "b"], laws={"a": "ka*q_a + kc*q_b", "b": "kc*q_a + kb*q_b"},
                 params={"ka": 2.0, "kb": 3.0, "kc": 0.5}, initial={"a": 0.1}))
    g.add(R("r1", 1.0))
    g.add(Zero("z2"))
    g.add(R("r2", 2.0))
    g.add(CField("ce", ("x", "y"), energy="k1*q_x**2/2 + k12*q_x*q_y + k2*q_y**4/4",
                 params={"k1": 1.0, "k12": 0.2, "k2": 5.0}, domain="translation"))
    g.add(Se("F", 1.0))
    g.add(One("j3"))
    g.add(IField("inf", ["p", "q"], laws={"p": "p_p/m1 - p_q/m12", "q": "p_q/m2 - p_p/m12"},
                 params={"m1": 1.0, "m2": 2.0, "m12": 10.0}, domain="rotation"))
    g.add(R("r3", 0.3))
    g.add(One("j4"))
    g.add(R("r4", 0.4))
    g.add(Sf("v2", 0.05))
    g.add(R("r5", 9.0))
    for tail, head in (("v_in", "z1"), ("z1", ("cf", "a")), ("z1", "r1"), (("cf", "b"), "z2"), ("z2", "r2"),
                       ("v2", ("ce", "x")), (("ce", "y"), "r5"),
                       ("F", "j3"), ("j3", ("inf", "p")), ("j3", "r3"), (("inf", "q"), "j4"), ("j4", "r4")):
        g.connect(tail, head)
    g.add_output("e_a", "e_bond2")
    return g


def equation_element():
    """EquationElement with states, held variables, fixed_step, params, units, descriptions."""
    g = BondGraph("chamber", description="equation-defined chamber with a sampled filter")
    g.add(Sf("mdot", 0.002, domain="pneumatic"))
    g.add(EquationElement(
        "ch", ports={"pn": "in"}, outputs={"e_pn": "P"},
        states={"P": "kc*f_pn - leak*(P - P0)"}, initial={"P": 1e5, "Pf": 1e5},
        units={"P": "Pa", "Pf": "Pa"}, held={"Pf": "Pf + h_step*(P - Pf)/tau"}, fixed_step=1e-3,
        params={"kc": Param("kc", 2e6, "Pa/kg"), "leak": 0.5, "P0": Param("P0", 1e5, "Pa"),
                "tau": Param("tau", 0.02, "s")},
        descriptions={"P": "chamber pressure"}, description="pneumatic chamber"))
    g.connect("mdot", ("ch", "pn"))
    g.add_output("P_filtered", "Pf", unit="Pa")
    return g


def pneumatic_chamber():
    """PneumaticChamber (thermal form) on a 0-junction with a leak R, guards and its own parameter."""
    g = BondGraph("cylinder", description="piston chamber with wall heat exchange and a leak")
    for name, value, unit in (("A", 2e-3, "m^2"), ("k1", 1.0, "1"), ("k2", 1.0, "1"), ("R", 287.0, "J/(kg K)"),
                              ("T", 293.0, "K"), ("gamma", 1.4, "1")):
        g.add_parameter(Param(name, value, unit))
    g.add(Sf("feed", 1e-3, domain="pneumatic"))
    g.add(Sf("stroke", 0.0, domain="translation"))
    g.add(Zero("gas"))
    g.add(R("leak", flow="1e-9*(e - 101325)", domain="pneumatic"))
    g.add(PneumaticChamber("cyl", pressure="P", length="0.1", volume="A*l", force="-(P - 101325)*A",
                           heat={"hA": "hA", "gamma": "gamma"}, initial_pressure=2e5,
                           initial_temperature=300.0, params={"hA": Param("hA", 2.0, "W/K")},
                           guards=[Guard("P_abs", "P", min=0.0, unit="Pa")], description="piston chamber"))
    g.connect("feed", "gas")
    g.connect("gas", "leak")
    g.connect("gas", ("cyl", "pn"))
    g.connect("stroke", ("cyl", "mech"))
    return g


ALL_BUILDERS = [msd_forms, law_forms, two_ports, fields, equation_element, pneumatic_chamber,
                mass_spring_damper, dc_motor, coupled_tanks, resistor_loop, lambda: resistor_loop(nonlinear=True)]


def fingerprint(eqs) -> dict:
    """Every field of a StateEquations as comparable text."""
    text = lambda seq: tuple(str(x) for x in seq)
    return {
        "name": eqs.name, "states": text(eqs.states), "inputs": text(eqs.inputs), "params": text(eqs.params),
        "outputs": tuple(eqs.outputs), "f": text(eqs.f), "h": text(eqs.h), "algebraic": text(eqs.algebraic),
        "residuals": text(eqs.residuals), "held": text(eqs.held), "held_update": text(eqs.held_update),
        "fixed_step": eqs.fixed_step, "param_values": dict(eqs.param_values),
        "initial_state": dict(eqs.initial_state), "input_defaults": dict(eqs.input_defaults),
        "held_initial": dict(eqs.held_initial), "units": dict(eqs.units), "descriptions": dict(eqs.descriptions),
        "owners": dict(eqs.owners), "input_functions": {k: str(v) for k, v in eqs.input_functions.items()},
        "report": str(eqs.report),
    }


def test_the_graphs_use_every_element_kind():
    kinds = {e.kind for build in ALL_BUILDERS for e in build().elements.values()}
    assert kinds == set(ELEMENT_KINDS)


@pytest.mark.parametrize("build", ALL_BUILDERS, ids=lambda b: getattr(b, "__name__", "nonlinear_loop"))
def test_round_trip_gives_identical_equations_and_bytes(build, tmp_path):
    g = build()
    path = tmp_path / "g.json"
    save(g, path)
    back = load(path)
    assert fingerprint(back.equations()) == fingerprint(g.equations())
    assert back.operating_point == g.operating_point and back.description == g.description
    again = tmp_path / "again.json"
    save(back, again)
    assert again.read_bytes() == path.read_bytes()
    assert load(again).to_dict() == g.to_dict()


def test_eq_element_keeps_fixed_step_held_and_units():
    back = graph_from_dict(graph_to_dict(equation_element()))
    eqs = back.equations()
    assert eqs.fixed_step == 1e-3 and back.elements["ch"].fixed_step == 1e-3
    assert [s.name for s in eqs.held] == ["Pf"] and eqs.held_initial["Pf"] == 1e5
    assert eqs.units["P"] == "Pa" and eqs.descriptions["P"] == "chamber pressure"
    assert eqs.input_functions == {}


def test_source_value_function_of_time_survives():
    back = graph_from_dict(graph_to_dict(msd_forms()))
    assert str(back.equations().input_functions["F"]) == "sin(t)"
    assert back.elements["F"].value == "sin(t)"


def test_file_is_plain_json_with_documented_top_level_keys(tmp_path):
    save(msd_forms(), tmp_path / "g.json")
    text = (tmp_path / "g.json").read_text(encoding="utf-8")
    data = json.loads(text)
    assert list(data) == ["format", "version", "name", "description", "elements", "bonds", "inputs",
                          "parameters", "outputs", "operating_point"]
    assert data["format"] == "bondcosim-graph" and data["version"] == 1
    assert data["bonds"][-1] == {"name": "force", "tail": ["F", ""], "head": ["j", ""]}
    assert '"tail": ["F", ""]' in text and text.endswith("}\n") and "\r" not in text
    # Same content as json.dumps(indent=2); only lists of scalars are kept on one line.
    assert json.loads(json.dumps(data, indent=2)) == data


# -- property tests ----------------------------------------------------------------
positive = st.floats(min_value=1e-6, max_value=1e6, allow_nan=False, allow_infinity=False)


@settings(deadline=None, max_examples=25)
@given(n=st.integers(min_value=1, max_value=4), m=positive, b=positive, compliance=positive,
       x0=st.floats(allow_nan=False, allow_infinity=False))
def test_chain_round_trip_property(n, m, b, compliance, x0):
    g = mass_spring_chain(n, m=m, b=b, compliance=compliance)
    g.add_output("x_last", f"q_k{n}", unit="m")
    g.operating_point["q_k1"] = x0
    text = dumps(g)
    back = graph_from_dict(json.loads(text))
    assert dumps(back) == text
    assert fingerprint(back.equations()) == fingerprint(g.equations())


names = st.from_regex(r"[A-Za-z_][A-Za-z0-9_]{0,8}", fullmatch=True)


@settings(deadline=None, max_examples=25)
@given(value=st.floats(allow_nan=False, allow_infinity=False), unit=st.text(max_size=12),
       description=st.text(max_size=30), pname=names)
def test_any_finite_value_and_any_text_round_trip_exactly(value, unit, description, pname):
    g = BondGraph("g", description=description)
    g.add(Se("F", value, unit=unit, description=description))
    g.add(One("j"))
    g.add(R("b", abs(value) or 1.0, unit=unit))
    g.connect("F", "j")
    g.connect("j", "b")
    if pname not in ("F", "b", "t", "h_step"):
        g.add_parameter(Param(pname, value, unit, description))
    text = dumps(g)
    back = graph_from_dict(json.loads(text))
    assert dumps(back) == text  # byte-identical, -0.0 and 5e-324 included
    assert math.copysign(1.0, back.elements["F"].value) == math.copysign(1.0, value)


# -- bad input: every problem named, with its JSON path ------------------------------
def good() -> dict:
    return graph_to_dict(msd_forms())


def problems_of(data) -> SchemaError:
    with pytest.raises(SchemaError) as info:
        graph_from_dict(data)
    return info.value


def test_unknown_kind_names_it_and_lists_the_known_kinds():
    data = good()
    data["elements"][2]["kind"] = "Spring"
    err = problems_of(data)
    assert err.path == "elements[2].kind"
    assert "'Spring'" in str(err) and "expected one of" in str(err)
    assert all(kind in str(err) for kind in ("CField", "MGY", "Se"))
    assert isinstance(err, GraphError) and isinstance(err, ValueError)


def test_bond_to_a_missing_port_names_the_port_and_lists_the_ports():
    data = graph_to_dict(two_ports())
    bond = next(b for b in data["bonds"] if b["head"][0] == "n")
    bond["head"][1] = "3"
    err = problems_of(data)
    i = data["bonds"].index(bond)
    assert err.path == f"bonds[{i}].head"
    assert "TF 'n' has no port '3'" in str(err) and "'1', '2'" in str(err)


def test_bond_to_a_missing_element_names_it_and_lists_the_elements():
    data = good()
    data["bonds"][0]["head"] = ["spring", ""]
    err = problems_of(data)
    assert err.path == "bonds[0].head"
    assert "no element named 'spring'" in str(err) and "F, j, m, b, k" in str(err)


def test_named_port_on_a_junction_or_one_port_is_rejected():
    data = good()
    data["bonds"][0]["tail"] = ["j", "x"]
    data["bonds"][1]["head"] = ["b", "x"]
    err = problems_of(data)
    assert "junction 'j' (1) has no named ports" in err.problems[0]
    assert "R 'b' has no port 'x'" in err.problems[1] and 'its only port is ""' in err.problems[1]


def test_duplicate_element_names():
    data = good()
    data["elements"][3]["name"] = "m"
    err = problems_of(data)
    assert err.path == "elements[3].name"
    assert "duplicate element name 'm'" in str(err) and "elements[2]" in str(err)


def test_duplicate_bond_and_output_names():
    data = good()
    data["bonds"][1]["name"] = data["bonds"][0]["name"]
    data["outputs"][1]["name"] = "x_err"
    err = problems_of(data)
    assert any(p.startswith("bonds[1]") and "duplicate name" in p for p in err.problems)
    assert any(p.startswith("outputs[1].name") and "duplicate output name 'x_err'" in p for p in err.problems)


def test_non_numeric_parameter_names_parameter_and_path():
    data = graph_to_dict(law_forms())
    data["elements"][2]["params"]["Ct"]["value"] = "abc"
    err = problems_of(data)
    assert err.path == "elements[2].params.Ct.value"
    assert "parameter 'Ct' of C 'tank'" in str(err) and '"abc"' in str(err) and "finite number" in str(err)


def test_non_numeric_graph_parameter_and_element_value():
    data = good()
    data["parameters"][0]["value"] = "0.1 m"
    data["elements"][2]["value"] = "two"
    err = problems_of(data)
    assert err.problems == [
        "elements[2].value: I 'm': expected a finite number, got \"two\" (a string)",
        "parameters[0].value: parameter 'x_ref': expected a finite number, got \"0.1 m\" (a string)",
    ]


def test_missing_top_level_key_and_missing_element_key():
    data = graph_to_dict(two_ports())
    del data["bonds"]
    del next(e for e in data["elements"] if e["kind"] == "TF")["modulus"]
    err = problems_of(data)
    assert "missing key 'bonds'" in str(err)
    assert any("missing key 'modulus' (required in TF element 'n')" in p for p in err.problems)


def test_unknown_key_suggests_the_close_one():
    data = good()
    data["elements"][2]["valu"] = data["elements"][2].pop("value")
    err = problems_of(data)
    assert err.path == "elements[2].valu" and "did you mean 'value'?" in str(err)


def test_wrong_format_tag_and_version():
    data = good()
    data["format"] = "fmi-model"
    err = problems_of(data)
    assert err.path == "format" and "'bondcosim-graph'" in str(err) and '"fmi-model"' in str(err)
    data = good()
    data["version"] = 2
    err = problems_of(data)
    assert err.path == "version" and "version 2 is not supported" in str(err)


def test_not_an_object():
    err = problems_of([1, 2])
    assert "expected a JSON object" in str(err) and "a list" in str(err)


def test_constructor_errors_are_collected_with_the_element_path():
    data = good()
    data["elements"][3]["effort"] = "b*f"  # value and effort both given
    data["elements"][1]["description"] = 3
    err = problems_of(data)
    assert err.problems[0] == "elements[1].description: 1 'j': expected a string, got 3 (a number)"
    assert err.problems[1].startswith("elements[3]: R 'b': give exactly one of value, effort= or flow=")


def test_three_problems_in_one_file_are_all_reported(tmp_path):
    data = good()
    data["elements"][2]["kind"] = "2"                            # 1: unknown kind
    data["elements"][3]["value"] = None                          # 2: not a number
    data["bonds"][3]["tail"] = ["Fx", ""]                        # 3: no such element
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(data, indent=2), encoding="utf-8")
    with pytest.raises(SchemaError) as info:
        load(path)
    err = info.value
    assert len(err.problems) == 3, err.problems
    assert str(path) in str(err) and "3 problems" in str(err)
    assert err.problems[0].startswith("elements[2].kind: unknown element kind '2'")
    assert err.problems[1] == "elements[3].value: R 'b': expected a finite number, got null"
    assert err.problems[2].startswith("bonds[3].tail: no element named 'Fx'")


def _set(path, value):
    """An edit of good() setting `value` at `path` (a tuple of keys/indices; None deletes)."""
    def edit(data):
        *parents, last = path
        for key in parents:
            data = data[key]
        if value is None:
            del data[last]
        else:
            data[last] = value
    return edit


@pytest.mark.parametrize("edit, path, fragment", [
    (_set(("format",), None), "", "missing key 'format'"),
    (_set(("version",), "1"), "version", 'integer format version (1), got "1" (a string)'),
    (_set(("name",), "2fast"), "name", "expected an identifier"),
    (_set(("elements",), {}), "elements", "expected a list, got {} (an object)"),
    (_set(("elements", 1), "j"), "elements[1]", 'expected an element: an object with keys kind, name; got "j"'),
    (_set(("elements", 1, "kind"), None), "elements[1]", "missing key 'kind'"),
    (_set(("elements", 1, "kind"), 1), "elements[1].kind", "expected an element kind (a string)"),
    (_set(("elements", 2, "domain"), "mechanical"), "elements[2].domain", "'translation', 'rotation'"),
    (_set(("elements", 2, "params"), [1]), "elements[2].params", "expected an object of parameter name"),
    (_set(("elements", 2, "params"), {"g": {"value": 9.81, "name": "gee"}}), "elements[2].params.g.name",
     "parameter 'g' says its name is 'gee'"),
    (_set(("elements", 2, "params"), {"g": {"val": 9.81}}), "elements[2].params.g",
     "missing key 'value' (required in parameter 'g')"),
    (_set(("bonds", 0, "tail"), "F"), "bonds[0].tail", "expected [element, port], two strings"),
    (_set(("bonds", 0, "tail"), ["F", "", "x"]), "bonds[0].tail", "expected [element, port]"),
    (_set(("bonds", 0, "name"), "m"), "bonds[0]", "duplicate name 'm'"),
    (_set(("inputs", 0, "default"), "high"), "inputs[0].default", "expected a finite number"),
    (_set(("outputs", 0, "expression"), " "), "outputs[0].expression", "expected an expression"),
    (_set(("outputs", 0, "unit"), None), None, None),  # optional keys may be left out
    (_set(("operating_point",), {"p_m": "zero"}), "operating_point.p_m", "expected a finite number"),
    (_set(("operating_point",), [0.0]), "operating_point", "expected an object of name -> a finite number"),
])
def test_each_malformed_entry_is_named_by_its_path(edit, path, fragment):
    data = good()
    edit(data)
    if path is None:
        graph_from_dict(data)
        return
    err = problems_of(data)
    assert err.path == path, err.problems
    assert fragment in err.problems[0], err.problems


def test_field_and_eq_entries_are_type_checked():
    data = graph_to_dict(fields())
    data["elements"][2]["ports"] = ["a", 3]
    data["elements"][6]["initial"] = {"x": "0"}
    eq = graph_to_dict(equation_element())
    eq["elements"][1]["ports"] = {"pn": "sideways"}
    eq["elements"][1]["fixed_step"] = -1e-3
    err = problems_of(data)
    assert [p.split(":")[0] for p in err.problems] == ["elements[2].ports", "elements[6].initial.x"]
    err = problems_of(eq)
    assert err.problems[0].startswith('elements[1].ports: Eq \'ch\': expected an object of port name -> "in"')
    assert err.problems[1] == "elements[1].fixed_step: Eq 'ch': expected a positive finite number, got -0.001 (a number)"


def test_bonds_of_a_broken_element_are_not_reported_twice():
    data = good()
    data["elements"][2]["kind"] = "Mass"
    err = problems_of(data)
    assert len(err.problems) == 1 and err.path == "elements[2].kind"


def test_malformed_json_gives_file_line_and_column(tmp_path):
    path = tmp_path / "broken.json"
    path.write_text('{\n  "format": "bondcosim-graph",\n  "version": 1,\n}\n', encoding="utf-8")
    with pytest.raises(SchemaError) as info:
        load(path)
    message = str(info.value)
    assert str(path) in message and "not valid JSON" in message and "line 4, column 1" in message


def test_duplicate_json_key_is_reported(tmp_path):
    text = dumps(msd_forms()).replace('"value": 2.0,', '"value": 2.0, "value": 3.0,', 1)
    path = tmp_path / "dup.json"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(SchemaError, match="key 'value' appears twice"):
        load(path)


def test_a_nan_source_value_never_reaches_a_file():
    """Refused when the element is made, so there is nothing unloadable to save."""
    with pytest.raises(ParameterError, match="'F'.*not a finite number"):
        Se("F", float("nan"))


# -- the schema: machine-readable, in step with the loader and the docs -------------------
def test_element_keys_match_the_constructors_and_the_schema():
    assert set(ELEMENT_KEYS) == set(ELEMENT_KINDS)
    for kind, cls in ELEMENT_KINDS.items():
        params = list(inspect.signature(cls).parameters)[1:]
        assert set(ELEMENT_KEYS[kind]) == set(params), kind
        schema_keys = set(SCHEMA["$defs"][f"element_{kind}"]["properties"])
        assert schema_keys == {"kind", "name"} | set(params), kind
    assert SCHEMA["$defs"]["element"]["properties"]["kind"]["enum"] == list(ELEMENT_KEYS)


def test_docs_describe_every_kind_and_their_example_loads():
    doc = (ROOT / "docs" / "json-schema.md").read_text(encoding="utf-8")
    for kind, keys in ELEMENT_KEYS.items():
        assert f"`{kind}`" in doc, kind
        for key in keys:
            assert f"`{key}`" in doc, (kind, key)
    example = re.search(r"```json\n(.*?)```", doc, re.DOTALL).group(1)
    g = graph_from_dict(json.loads(example))
    eqs = g.equations()
    # dp/dt = F - b p/m - k q, dq/dt = p/m (mass_spring_damper's docstring)
    assert [str(f) for f in eqs.f] == ["F - b*p_m/m - k*q_k", "p_m/m"]
    assert dumps(g) == example


@pytest.mark.parametrize("build", ALL_BUILDERS, ids=lambda b: getattr(b, "__name__", "nonlinear_loop"))
def test_written_graphs_validate_against_the_json_schema(build):
    jsonschema = pytest.importorskip("jsonschema")
    jsonschema.Draft202012Validator.check_schema(SCHEMA)
    jsonschema.Draft202012Validator(SCHEMA).validate(graph_to_dict(build()))


def test_json_schema_rejects_what_the_loader_rejects():
    jsonschema = pytest.importorskip("jsonschema")
    validator = jsonschema.Draft202012Validator(SCHEMA)
    edits = [
        lambda d: d["elements"][2].__setitem__("kind", "Spring"),
        lambda d: d["elements"][2].__setitem__("value", "two"),
        lambda d: d["elements"][2].__setitem__("law", "p/m"),         # value and law
        lambda d: d["elements"][2].__setitem__("valu", 1.0),
        lambda d: d["bonds"][0].__setitem__("tail", ["F"]),
        lambda d: d.__setitem__("format", "other"),
        lambda d: d.pop("elements"),
    ]
    for edit in edits:
        data = good()
        edit(data)
        assert not validator.is_valid(data)
        with pytest.raises(SchemaError):
            graph_from_dict(data)
