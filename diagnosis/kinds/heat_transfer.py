"""``heat_transfer`` at a pneumatic or thermal 0-junction.

* At a 0-junction holding a :class:`~bondgraph.elements.PneumaticChamber`: the chamber's thermal
  form (the gas temperature becomes a state exchanging heat with the wall; fitted: the wall
  conductance hA, W/K, and the ratio of specific heats), one candidate per chamber.
* At other pneumatic / thermal 0-junctions: the gas in a chamber is compressed nearly
  adiabatically in fast transients and nearly isothermally in slow ones.  Newtonian heat exchange
  with the walls is represented, to first order in the temperature excursion, by an extra
  compliance :math:`C_{th}` (the difference between the isothermal and the adiabatic compliance,
  :math:`(1 - 1/\\kappa) V / (R T)` for a chamber of volume V) reached through a thermal
  resistance, i.e. a 1-junction with an R and a C hung on the chamber's 0-junction;
  :math:`\\tau_{th} = R_{th} C_{th}` is the thermal time constant :math:`m c_v / (h A)`.  We fit
  :math:`C_{th}` and :math:`\\tau_{th}`; the C branch starts at the chamber's initial pressure.
"""
from __future__ import annotations

import numpy as np

from bondgraph import C, One, R
from bondgraph.params import DOMAINS

from ..catalogue_common import ParamSpec, fresh_name, junction_domain, junction_elements, junction_units
from .base import Kind, Proposal, hang, register


@register
class HeatTransfer(Kind):
    name = "heat_transfer"
    doors = ("0",)

    def propose(self, site):
        graph, j, scales = site.graph, site.name, site.scales
        chambers = [el for el, _ in junction_elements(graph, j) if el.kind == "PneumaticC" and el.heat is None]
        out = [_chamber_heat(site, chamber) for chamber in chambers]
        dom = junction_domain(graph, j)
        if dom in ("pneumatic", "thermal") and not chambers:
            e_unit, _ = junction_units(graph, j)
            E, F = scales.effort, scales.flow
            e = site.effort
            e0 = float(e[0]) if e is not None else 0.0
            c_th = F * scales.span / max(E, 1e-12) * 0.05
            out.append(Proposal(
                constants=((fresh_name(site.taken, f"P_th0_{j}"), e0, e_unit, f"initial pressure of the thermal branch at {j}"),),
                params=(ParamSpec(fresh_name(site.taken, f"C_th_{j}"), c_th, c_th * 1e-3, c_th * 1e3,
                                  DOMAINS[dom].compliance,
                                  f"{'heat capacity' if dom == 'thermal' else 'thermal compliance'} at {j}"),
                        ParamSpec(fresh_name(site.taken, f"tau_th_{j}"), scales.span / 10, scales.dt / 2,
                                  scales.span * 10, "s", f"thermal time constant at {j}"))))
        return out

    def build(self, graph, cand, values):
        j = cand.place.name
        p = [spec.name for spec in cand.params]
        if cand.target is not None:            # the chamber's own thermal form
            chamber = graph.elements[cand.target]
            return graph.with_element(cand.target, heat={"hA": p[0], "gamma": p[1]},
                                      initial_temperature=float(next(iter(cand.initial.values()))),
                                      description=f"{chamber.description} (with wall heat exchange)".strip())
        dom = junction_domain(graph, j)
        branch, r_th, c_th = f"heat_{j}", f"R_th_{j}", f"C_th_el_{j}"
        graph = hang(graph, One(branch, description=f"heat exchange branch of the chamber at {j}"), j)
        graph = hang(graph, R(r_th, flow=f"e*{p[0]}/{p[1]}", domain=dom,
                              description=f"thermal resistance tau_th / C_th at {j}"), branch)
        return hang(graph, C(c_th, law=f"{cand.constants[0][0]} + q/{p[0]}", domain=dom, state=f"q_th_{j}",
                             initial=0.0, description=f"thermal compliance at {j}"), branch)

    def explain(self, cand, values, show):
        j = cand.place.name
        p = [spec.name for spec in cand.params]
        if cand.target is not None:
            return (f"the gas in {cand.target} heats up when compressed or filled and exchanges heat with its "
                    f"walls through a conductance of {show(p[0])} (ratio of specific heats {show(p[1])}): "
                    f"heat transfer in {cand.target} at {j}")
        if cand.params[0].unit == DOMAINS["thermal"].compliance:     # a thermal junction: a second mass
            return (f"the temperature at {j} relaxes with a time constant of {show(p[1])} after each change as "
                    f"{j} exchanges heat with a thermal mass the model leaves out (heat capacity {show(p[0])}): "
                    f"heat transfer at {j}")
        return (f"the pressure at {j} relaxes with a time constant of {show(p[1])} after each change as the "
                f"gas exchanges heat with its walls (thermal compliance {show(p[0])}): heat transfer at {j}")


def _chamber_heat(site, chamber) -> Proposal:
    """The candidate of a pneumatic chamber's thermal form, with the wall conductance hA (W/K)
    scaled so that the heat capacity of the gas at the junction's mean pressure relaxes in a
    tenth of the record."""
    graph, scales = site.graph, site.scales
    params = {n: p.value for n, p in graph.parameters().items()}
    t_wall = float(params.get(chamber.temperature, 293.0))
    e = site.effort
    pressure = float(np.mean(e)) if e is not None else chamber.initial_pressure
    heat_capacity = pressure * _chamber_volume(graph, chamber, params) / (0.4 * t_wall)   # m c_v, J/K
    h_a, gamma = fresh_name(site.taken, f"hA_{chamber.name}"), fresh_name(site.taken, f"gamma_{chamber.name}")
    per_second = heat_capacity / scales.span          # hA that relaxes the gas over the whole record
    return Proposal(target=chamber.name, initial={chamber.gas_state: t_wall},
                    starts=({h_a: 100 * per_second, gamma: 1.4}, {h_a: per_second, gamma: 1.4}),
                    params=(ParamSpec(h_a, 10 * per_second, 0.01 * per_second, 2 * heat_capacity / scales.dt, "W/K",
                                      f"heat conductance from the gas in {chamber.name} to its wall"),
                            ParamSpec(gamma, 1.4, 1.0, 1.67, "1", f"ratio of specific heats of the gas in {chamber.name}")))


def _chamber_volume(graph, chamber, params) -> float:
    """Volume of a pneumatic chamber at the model's initial state, m^3 (its volume law at its length)."""
    import sympy as sp
    from bondgraph.symbols import parse
    initial = dict(graph.equations().initial_state)
    table = {name: sym for name, sym in graph.names().items()}
    numbers = {table[n]: v for n, v in {**params, **initial}.items() if n in table}
    length = parse(chamber.length, table, owner=f"{chamber.name} length").xreplace(numbers)
    volume = parse(chamber.volume, {**table, "l": sp.Symbol("l")}, owner=f"{chamber.name} volume")
    value = complex(volume.xreplace(numbers).subs(sp.Symbol("l"), length).evalf())
    return abs(value.real) if np.isfinite(value.real) and value.real != 0 else 1e-4
