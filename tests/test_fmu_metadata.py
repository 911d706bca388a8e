"""Real units and metadata in exported FMUs (issue 12, part 4): BaseUnit exponents and
factor/offset checked against the SI definitions (BIPM SI Brochure, 9th ed., Table 4 and
the degree = pi/180 rad), every variable with a unit and a description, nominal values,
min/max from the graph's bounds, DefaultExperiment and authorship; fmpy reads them."""
from __future__ import annotations

import math
import xml.etree.ElementTree as ET
import zipfile

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.validation import validate_fmu

import plants.library as library
from bondgraph.units import base_unit
from fmus import export

VERSIONS = (2, 3)
#: Unit -> (BaseUnit exponents, factor, offset), from the SI definitions.
SI = {
    "N": ({"kg": 1, "m": 1, "s": -2}, 1.0, 0.0),
    "Pa": ({"kg": 1, "m": -1, "s": -2}, 1.0, 0.0),
    "V": ({"kg": 1, "m": 2, "s": -3, "A": -1}, 1.0, 0.0),
    "H": ({"kg": 1, "m": 2, "s": -2, "A": -2}, 1.0, 0.0),
    "N m s/rad": ({"kg": 1, "m": 2, "s": -1, "rad": -1}, 1.0, 0.0),
    "J/(kg K)": ({"m": 2, "s": -2, "K": -1}, 1.0, 0.0),
    "deg": ({"rad": 1}, math.pi / 180, 0.0),
    "bar": ({"kg": 1, "m": -1, "s": -2}, 1e5, 0.0),
    "rpm": ({"rad": 1, "s": -1}, 2 * math.pi / 60, 0.0),
    "degC": ({"K": 1}, 1.0, 273.15),
    "mm": ({"m": 1}, 1e-3, 0.0),
    "cd": ({"cd": 1}, 1.0, 0.0),
    "1": ({}, 1.0, 0.0),
}


@pytest.mark.parametrize("unit", SI)
def test_base_unit_matches_the_si_definitions(unit):
    exps, factor, offset = base_unit(unit)
    assert exps == SI[unit][0]
    assert factor == pytest.approx(SI[unit][1], rel=1e-15) and offset == SI[unit][2]


def _xml(path):
    return ET.fromstring(zipfile.ZipFile(path).read("modelDescription.xml"))


@pytest.fixture(scope="module")
def fmus(exported_fmu):
    return {(m, v): exported_fmu(m, v)
            for m in ("pam", "dc-motor", "mass-spring-damper", "resistor-loop-nl") for v in VERSIONS}


@pytest.mark.parametrize("version", VERSIONS)
@pytest.mark.parametrize("model", ("pam", "dc-motor", "mass-spring-damper", "resistor-loop-nl"))
def test_every_unit_has_its_base_unit_and_every_variable_a_unit_and_description(fmus, model, version):
    path = fmus[model, version]
    assert validate_fmu(str(path)) == []
    root = _xml(path)
    units = {}
    for u in root.find("UnitDefinitions"):
        base = u.find("BaseUnit")
        exps = {k: int(v) for k, v in base.attrib.items() if k not in ("factor", "offset")}
        units[u.get("name")] = (exps, float(base.get("factor", 1.0)), float(base.get("offset", 0.0)))
    for name, expected in SI.items():
        if name in units:
            assert units[name][0] == expected[0] and units[name][1] == pytest.approx(expected[1])
    tag = "ScalarVariable" if version == 2 else "Float64"
    variables = list(root.find("ModelVariables").iter(tag))
    assert variables
    for v in variables:
        unit = (v.find("Real") if version == 2 else v).get("unit")
        assert unit in units, v.get("name")
        assert v.get("description"), v.get("name")
    md = read_model_description(str(path))   # fmpy reads the same
    fm = {u.name: u.baseUnit for u in md.unitDefinitions}
    if "deg" in fm:
        assert fm["deg"].rad == 1 and fm["deg"].factor == pytest.approx(math.pi / 180)


@pytest.mark.parametrize("version", VERSIONS)
def test_nominal_min_max_experiment_and_authorship(fmus, version):
    md = read_model_description(str(fmus["pam", version]))
    var = {v.name: v for v in md.modelVariables}
    assert float(var["P_1"].nominal) == 0.1013e6 and float(var["P_1"].min) == 0.0  # guard P_1 >= 0
    assert float(var["J"].min) == 0.0 and float(var["J"].nominal) == 4.263e-4     # inertia >= 0
    assert var["psi"].unit == "deg" and var["k"].unit == "1"
    assert md.author == "bondcosim" and md.version == "1.0" and md.license == "MIT"
    assert md.generationTool.startswith("bondcosim")
    # pam has a fixed 0.25 ms sub-step; its scheme samples at 1 ms
    assert (md.defaultExperiment.startTime, md.defaultExperiment.stepSize) == ("0.0", "0.001")
    msd = read_model_description(str(fmus["mass-spring-damper", version]))
    var = {v.name: v for v in msd.modelVariables}
    assert float(var["m"].min) == 0.0 and float(var["k"].min) == 0.0 and float(var["b"].min) == 0.0
    # m = 1 kg, b = 0.4 N s/m, k = 4 N/m: poles -0.2 +- 1.99j; 5 / 0.2 s = 25 s -> 50 s (1-2-5)
    assert float(msd.defaultExperiment.stopTime) == 50.0
    assert float(msd.defaultExperiment.stepSize) == 0.05
    dc = read_model_description(str(fmus["dc-motor", version]))
    assert {v.name: v for v in dc.modelVariables}["n"].unit == "1"


def test_state_nominals_reach_model_exchange(fmus):
    # fmpy's ME driver asks for the nominals (fmi2GetNominalsOfContinuousStates); the
    # result still matches the analytic mass-spring-damper step response
    path = fmus["mass-spring-damper", 2]
    res = simulate_fmu(str(path), fmi_type="ModelExchange", stop_time=5.0, output_interval=0.01,
                       start_values={"F": 2.0}, output=["q_k"])
    m, b, k = 1.0, 0.4, 4.0
    wn, zeta = math.sqrt(k / m), b / (2 * math.sqrt(k * m))
    wd = wn * math.sqrt(1 - zeta ** 2)
    t = res["time"]
    ref = 2.0 / k * (1 - np.exp(-zeta * wn * t) * (np.cos(wd * t) + zeta * wn / wd * np.sin(wd * t)))
    assert np.max(np.abs(res["q_k"] - ref)) < 1e-4


@pytest.mark.parametrize("unit, expected", [
    ("N s", "N"), ("m", "m/s"), ("mm/s", "mm/(s s)"), ("J/(kg K)", "J/(kg K s)"), ("", "1/s"),
    ("s", "1"), ("Pa", "Pa/s")])
def test_derivative_units_parse_and_mean_per_second(unit, expected):
    from bondgraph.units import parse_unit
    from fmus.layout import derivative_unit
    assert derivative_unit(unit) == expected
    if unit:   # d/dt divides by seconds: same scale, dimension s^-1 more
        a, b = parse_unit(unit), parse_unit(expected)
        assert b.scale == pytest.approx(a.scale)
        assert [y - x for x, y in zip(a.dimension, b.dimension)] == [0, 0, -1, 0, 0, 0, 0, 0]


def test_unknown_unit_text_is_declared_without_base_unit(tmp_path):
    from bondgraph import Param
    g = library.build("mass-spring-damper")
    g.add_parameter(Param("gain", 2.0, "counts", "a unit the grammar does not know"))
    g.add_output("counted", "gain*q_k", unit="counts", description="position in counts")
    path = export(g, tmp_path / "c.fmu")
    assert validate_fmu(str(path)) == []
    unit = [u for u in _xml(path).find("UnitDefinitions") if u.get("name") == "counts"][0]
    assert unit.find("BaseUnit") is None
