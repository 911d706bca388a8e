"""The pneumatic chamber as a two-port C-field, against closed-form gas laws."""
from __future__ import annotations

import numpy as np
import pytest

from bondgraph import BondGraph, DerivationError, Param, PneumaticChamber, Sf, Zero
from bondgraph.numerics import simulate
from bondgraph.io_json import graph_from_dict

R_AIR, T_WALL = 287.0, 293.0
A_PISTON, L0, P0 = 2e-3, 0.1, 2e5     # m^2, m, Pa
H_A = 2.0                             # W/K, wall heat conductance


def piston(mdot: float, speed: float, *, heat=None, k=1.0, t_gas=T_WALL) -> BondGraph:
    """A piston chamber V = A l fed with a constant mass flow, its length driven at a constant speed."""
    g = BondGraph("piston", description="piston chamber on prescribed flows")
    for name, value, unit in (("A", A_PISTON, "m^2"), ("k1", k, "1"), ("k2", k, "1"), ("R", R_AIR, "J/(kg K)"),
                              ("T", T_WALL, "K"), ("hA", H_A, "W/K"), ("gamma", 1.4, "1")):
        g.add_parameter(Param(name, value, unit))
    g.add(Sf("feed", mdot, domain="pneumatic"))
    g.add(Sf("stroke", speed, domain="translation"))
    g.add(Zero("gas", description="chamber mass balance"))
    g.add(PneumaticChamber("cyl", pressure="P", length=f"{L0} + {speed}*t", volume="A*l",
                           force="-(P - 101325)*A", heat=heat, initial_pressure=P0, initial_temperature=t_gas))
    g.connect("feed", "gas")
    g.connect("gas", ("cyl", "pn"))
    g.connect("stroke", ("cyl", "mech"))
    g.add_output("p", "P", unit="Pa")
    return g


def run(g, t_end=0.2):
    res = simulate(g, (0.0, t_end), output_interval=t_end / 100, rtol=1e-10, atol=1e-6)
    return res.t, res


def test_isothermal_filling_at_fixed_volume_is_linear_in_time():
    t, res = run(piston(mdot=1e-3, speed=0.0))
    expected = P0 + R_AIR * T_WALL * 1e-3 * t / (A_PISTON * L0)      # P V = m R T, V fixed
    np.testing.assert_allclose(res["p"], expected, rtol=1e-9)


def test_closed_polytropic_compression_keeps_p_v_to_the_k():
    t, res = run(piston(mdot=0.0, speed=-0.2, k=1.3))
    volume = A_PISTON * (L0 - 0.2 * t)
    np.testing.assert_allclose(res["p"], P0 * (A_PISTON * L0 / volume) ** 1.3, rtol=1e-8)


def test_thermal_form_relaxes_the_gas_temperature_exponentially():
    t, res = run(piston(mdot=0.0, speed=0.0, heat={"hA": "hA", "gamma": "gamma"}, t_gas=350.0))
    heat_capacity = P0 * A_PISTON * L0 / (R_AIR * 350.0) * R_AIR / 0.4   # m c_v, J/K (closed, rigid)
    t_gas = T_WALL + (350.0 - T_WALL) * np.exp(-t * H_A / heat_capacity)
    np.testing.assert_allclose(res["T_cyl"], t_gas, rtol=1e-7)
    np.testing.assert_allclose(res["p"], P0 * t_gas / 350.0, rtol=1e-7)   # P / T_g constant


@pytest.mark.parametrize("h_a, k", [(1e5, 1.0), (1e-6, 1.4)])
def test_thermal_form_tends_to_isothermal_and_adiabatic(h_a, k):
    """Fast heat exchange: isothermal at the wall; none: adiabatic with gamma (filling and compressing)."""
    thermal = piston(mdot=2e-3, speed=-0.1, heat={"hA": str(h_a), "gamma": "gamma"})
    polytropic = piston(mdot=2e-3, speed=-0.1, k=k)
    np.testing.assert_allclose(run(thermal)[1]["p"], run(polytropic)[1]["p"], rtol=2e-3)


def test_round_trip_and_with_heat():
    g = piston(mdot=1e-3, speed=0.0)
    again = graph_from_dict(g.to_dict())
    assert again.to_dict() == g.to_dict()
    chamber = g.elements["cyl"].with_heat("hA", "gamma", initial_temperature=300.0)
    assert chamber.gas_state == "T_cyl" and chamber.initial_temperature == 300.0
    assert chamber.to_dict()["heat"] == {"hA": "hA", "gamma": "gamma"}


def test_heat_needs_ha_and_gamma():
    with pytest.raises(DerivationError, match="'hA' and 'gamma'"):
        PneumaticChamber("c", pressure="P", length="1", volume="l", force="P", heat={"tau": "1"})
