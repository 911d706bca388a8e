"""Unit conversion between connected ports (issue 12, part 5): through the unit grammar
(bondgraph.units) when units differ but are convertible, a per-connection override for
sources that declare no or a wrong unit, the clear error for true mismatches.  Reference
values: the SI definitions (1 deg = pi/180 rad, 1 bar = 1e5 Pa, 0 degC = 273.15 K)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from bondgraph.errors import CosimError
from cosim import PI, CoSimulation, Constant, FMUComponent, Table
from cosim_helpers import handwritten_msd


def _pi(name, unit_in, unit_out="1"):
    # kp = 1, ki = 0: u = r - y_m, in the input's unit
    return PI(name, kp=1.0, ki=0.0, unit_in=unit_in, unit_out=unit_out)


@pytest.mark.parametrize("value, unit_from, unit_to, expected", [
    (90.0, "deg", "rad", math.pi / 2),
    (2.0, "bar", "Pa", 2e5),
    (20.0, "degC", "K", 293.15),
    (1500.0, "N mm", "N m", 1.5),
    (60.0, "rpm", "rad/s", 2 * math.pi),
])
def test_convertible_units_are_converted(value, unit_from, unit_to, expected):
    sim = CoSimulation([Constant("r", value, unit_from), Constant("z", 0.0, unit_to),
                        _pi("c", unit_to)],
                       [("r.y", "c.r"), ("z.y", "c.y_m")], step=0.1)
    res = sim.run(0.2)
    assert res["c.r"] == pytest.approx(np.full(3, expected), rel=1e-15)
    assert res["c.u"] == pytest.approx(np.full(3, expected), rel=1e-15)
    assert res["r.y"][0] == value                        # the source keeps its own unit
    assert sim.conversions["c.r"][:2] == (unit_from, unit_to)
    assert f"r.y -> c.r [{unit_from} -> {unit_to}]" in res.info["connections"]


def test_conversion_reaches_an_fmu_input_and_its_response(tmp_path_factory):
    # a force given in kN drives the hand-written mass-spring-damper FMU (F in N): its
    # response must equal the one to the same force given in N
    path = handwritten_msd(tmp_path_factory)
    runs = {}
    for unit, value in (("kN", 0.002), ("N", 2.0)):
        sim = CoSimulation([Table("f", [0.0], [value], unit=unit), FMUComponent(path, "plant")],
                           [("f.y", "plant.F")], step=1e-2)
        runs[unit] = sim.run(1.0)
    assert np.array_equal(runs["kN"]["plant.F"], runs["N"]["plant.F"])
    np.testing.assert_array_equal(runs["kN"]["plant.x"], runs["N"]["plant.x"])


def test_true_mismatch_stays_an_error_with_a_hint():
    with pytest.raises(CosimError, match=r"unit mismatch: 'r.y' \[1\] -> 'c.r' \[N\]: dimensions "
                                         r"1 and kg m s\^-2.*\{'unit': 'N'\}.*'convert': False"):
        CoSimulation([Constant("r", 3.0, "1"), _pi("c", "N")], [("r.y", "c.r")], step=0.1)
    with pytest.raises(CosimError, match=r"'r.y' \[furlong\] -> 'c.r' \[m\].*unknown symbol"):
        CoSimulation([Constant("r", 3.0, "furlong"), _pi("c", "m")], [("r.y", "c.r")], step=0.1)


def test_per_connection_override_for_third_party_units():
    # a third-party output declared dimensionless that is really a force
    blocks = lambda: [Constant("r", 3.0, "1"), Constant("z", 0.0, "N"), _pi("c", "N")]
    res = CoSimulation(blocks(), [("r.y", "c.r", {"unit": "kN"}), ("z.y", "c.y_m")],
                       step=0.1).run(0.1)
    assert res["c.r"][0] == 3000.0                      # 3 kN in N
    res = CoSimulation(blocks(), [("r.y", "c.r", {"unit": "N"}), ("z.y", "c.y_m")],
                       step=0.1).run(0.1)
    assert res["c.r"][0] == 3.0
    res = CoSimulation(blocks(), [("r.y", "c.r", {"convert": False})], step=0.1).run(0.1)
    assert res["c.r"][0] == 3.0


def test_bad_connection_options_are_named():
    with pytest.raises(CosimError, match=r"connections\[0\]: unknown option\(s\) 'units'; "
                                         r"expected unit, convert"):
        CoSimulation([Constant("r", 3.0, "1"), _pi("c", "N")], [("r.y", "c.r", {"units": "N"})],
                     step=0.1)
    with pytest.raises(CosimError, match=r"third element must be a dict"):
        CoSimulation([Constant("r", 3.0, "1"), _pi("c", "N")], [("r.y", "c.r", "N")], step=0.1)
