"""Bad input gets a clear error naming the offending thing (issue 2, section 9)."""
import pytest

from bondgraph import (BondGraph, C, DuplicateNameError, ExpressionError, GraphError, I, JunctionError, MSe,
                       One, Param, ParameterError, PortError, R, Se, TF, Zero)


def _msd():
    g = BondGraph("msd")
    for e in (Se("F"), One("j"), I("m", 1.0), R("b", 0.5)):
        g.add(e)
    return g


def test_duplicate_element_name():
    g = _msd()
    with pytest.raises(DuplicateNameError, match="'m'") as info:
        g.add(C("m", 1.0))
    assert info.value.name == "m"


def test_duplicate_bond_name():
    g = _msd()
    g.connect("F", "j", name="input")
    with pytest.raises(DuplicateNameError, match="'input'"):
        g.connect("j", "m", name="input")


def test_bond_to_missing_element():
    g = _msd()
    with pytest.raises(PortError, match="'spring'") as info:
        g.connect("j", "spring")
    assert info.value.element == "spring" and "elements are" in str(info.value)


def test_bond_to_missing_port():
    g = _msd()
    g.add(TF("gear", 2.0))
    with pytest.raises(PortError, match="no port '3'") as info:
        g.connect("j", ("gear", "3"))
    assert info.value.port == "3" and "'1'" in str(info.value)


def test_port_used_twice():
    g = _msd()
    g.connect("j", "m")
    with pytest.raises(PortError, match="already has a bond"):
        g.connect("F", "m")


def test_junction_with_one_bond():
    g = _msd()
    g.add(Zero("dangling"))
    g.connect("F", "j")
    g.connect("j", "m")
    g.connect("j", "b")
    g.connect("j", "dangling")
    with pytest.raises(JunctionError, match="'dangling'") as info:
        g.equations()
    assert info.value.element == "dangling"


def test_unconnected_element_is_named():
    g = _msd()
    g.connect("F", "j")
    g.connect("j", "m")
    with pytest.raises(GraphError, match="R 'b'"):
        g.equations()


@pytest.mark.parametrize("value", ["heavy", None, float("nan"), [1.0]])
def test_non_numeric_parameter(value):
    with pytest.raises(ParameterError, match="'mass'|mass"):
        Param("mass", value)


def test_non_numeric_element_value():
    with pytest.raises(ParameterError, match="'m'"):
        I("m", "heavy")


def test_parameters_with_one_name_but_different_values():
    g = _msd()
    g.add(MSe("drag", "c*f_m", params={"c": 1.0}))
    g.add(MSe("lift", "c*2", params={"c": 2.0}))
    with pytest.raises(DuplicateNameError, match="'c'"):
        g.names()


def test_expression_that_does_not_parse():
    g = BondGraph("bad_expr")
    g.add(Se("F", "sin(t"))
    g.add(I("m", 1.0))
    g.connect("F", "m")
    with pytest.raises(ExpressionError, match="input F") as info:
        g.equations()
    assert info.value.expression == "sin(t"


def test_expression_with_unknown_name():
    g = _msd()
    g.add(MSe("drag", "c*f_m*velocityy"))
    for a, b in (("F", "j"), ("j", "m"), ("j", "b"), ("drag", "j")):
        g.connect(a, b)
    with pytest.raises(ExpressionError, match="velocityy") as info:
        g.equations()
    assert set(info.value.unknown) == {"c", "velocityy"} and "drag" in info.value.owner


def test_every_bad_expression_is_reported_at_once():
    g = _msd()
    g.add(MSe("one", "x1"))
    g.add(MSe("two", "x2"))
    for a, b in (("F", "j"), ("j", "m"), ("j", "b"), ("one", "j"), ("two", "j")):
        g.connect(a, b)
    with pytest.raises(ExpressionError) as info:
        g.equations()
    assert "x1" in str(info.value) and "x2" in str(info.value)


def test_unknown_domain():
    with pytest.raises(ParameterError, match="'mechanical'.*translation"):
        I("m", 1.0, domain="mechanical")


def test_bad_names():
    with pytest.raises(GraphError, match="'2m'"):
        I("2m", 1.0)
    with pytest.raises(GraphError):
        BondGraph("my model")


def test_bad_output_expression_names_the_output():
    g = _msd()
    for a, b in (("F", "j"), ("j", "m"), ("j", "b")):
        g.connect(a, b)
    g.add_output("speed", "p_m/mm")
    with pytest.raises(ExpressionError, match="output 'speed'.*mm"):
        g.equations()


def test_non_numeric_source_value_and_input_default():
    with pytest.raises(ParameterError, match="'F'"):
        Se("F", [1.0])
    g = BondGraph("inputs")
    with pytest.raises(ParameterError, match="'u'"):
        g.add_input("u", default="abc")


def test_param_object_keeps_its_unit_and_description():
    m = I("m", Param("m", 2.0, "kg", "cart mass"))
    (param,) = m.parameters()
    assert (param.value, param.unit, param.description) == (2.0, "kg", "cart mass")


def test_field_initial_value_for_a_missing_port():
    from bondgraph import CField, DerivationError
    with pytest.raises(DerivationError, match="spring2.*for c, which are not ports"):
        CField("spring2", ["a", "b"], energy="q_a**2 + q_b**2", initial={"c": 1.0})


def test_source_value_of_numpy_type_round_trips_as_a_number():
    import numpy as np
    from bondgraph.io_json import graph_from_dict, graph_to_dict
    g = BondGraph("np_value")
    g.add(Se("F", np.int64(3)))
    g.add(I("m", 1.0))
    g.connect("F", "m")
    again = graph_from_dict(graph_to_dict(g)).equations()
    assert dict(again.input_defaults) == {"F": 3.0} and not again.input_functions
