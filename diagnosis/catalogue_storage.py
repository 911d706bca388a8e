"""Kinds acting on storage and flows: leak and heat transfer at a 0-junction, nonlinear stiffness
and backlash of a C element at a junction.

* ``leak``: an R from the 0-junction (common effort = pressure ``e``) to the
  ambient, :math:`f = c_{leak} (e - P_{amb})`; for pneumatic pseudo-bonds a mass
  flow proportional to the pressure difference.  :math:`P_{amb}` is fixed:
  101325 Pa for a pneumatic junction whose mean pressure exceeds 50 kPa
  (absolute pressures), else 0 (gauge pressures, other domains).
* ``heat_transfer`` at a 0-junction holding a
  :class:`~bondgraph.elements.PneumaticChamber`: the chamber's thermal form (the
  gas temperature becomes a state exchanging heat with the wall; fitted: the
  wall conductance hA, W/K, and the ratio of specific heats).
* ``heat_transfer`` at other pneumatic / thermal 0-junctions: the gas in a chamber
  is compressed nearly adiabatically in fast transients and nearly
  isothermally in slow ones.  Newtonian heat exchange with the walls is
  represented, to first order in the temperature excursion, by an extra
  compliance :math:`C_{th}` (the difference between the isothermal and the
  adiabatic compliance, :math:`(1 - 1/\\kappa) V / (R T)` for a chamber of volume
  V) reached through a thermal resistance, i.e. a 1-junction with an R and a
  C hung on the chamber's 0-junction; :math:`\\tau_{th} = R_{th} C_{th}` is the
  thermal time constant :math:`m c_v / (h A)`.  We fit :math:`C_{th}` and
  :math:`\\tau_{th}`; the C branch starts at the chamber's initial pressure.
* ``nonlinear_stiffness``: the C's law gets a cubic term, :math:`e = \\Phi(q) + k_3 q^3`, and
  its own linear value is refitted with it (a linear C's stiffness or compliance, named
  as the element; a linear term added to a law): a linear model identified from data
  carries the cubic term's average in its linear value.
* ``backlash``: the C's law acts on the displacement beyond a play of
  :math:`\\pm b`: :math:`e = \\Phi(q - \\mathrm{clip}(q, -b, b))` (a compliant
  transmission with a dead zone of total width 2b).
* ``saturation`` of a C's content :math:`q` (the storage is full, an axis is at
  its end): at a 1-junction, end stops, an R whose effort
  :math:`k_{stop} (\\max(q - q_{max}, 0) + \\min(q - q_{min}, 0))` pushes back
  beyond either limit; at a 0-junction, an overflow, an R whose flow
  :math:`k_{of} \\max(q - q_{max}, 0)` spills what exceeds the limit.  The
  stiffnesses are fixed, not fitted: :math:`k_{stop}` 30 times the spring's
  stiffness scale, :math:`k_{of}` one fifth of a sample's worth per second, so
  the content stays within a few per cent of the limit.
"""
from __future__ import annotations

import numpy as np

from bondgraph.params import DOMAINS

from .catalogue_common import ParamSpec, fresh_name, junction_domain, junction_elements, junction_units, substitute
from .errors import DiagnosisError

__all__ = ["STORAGE_KINDS", "make_storage", "build_storage", "explain_storage"]

STORAGE_KINDS = ("leak", "heat_transfer", "backlash", "nonlinear_stiffness")   # + saturation at a C
P_AMBIENT = 101325.0  # Pa


def make_storage(graph, place, scales, taken, values=None) -> list[dict]:
    """Candidate prototypes for a junction: flow kinds at a 0-junction, stiffness kinds for each C on it
    (`values`: nominal values at the junction, :func:`~diagnosis.catalogue_scales.junction_scales`)."""
    values = values or {}
    j = place.name
    dom = junction_domain(graph, j)
    e_unit, f_unit = junction_units(graph, j)
    E, F = scales.effort, scales.flow
    protos = []
    if graph.elements[j].kind == "0":
        first_bond = graph.bonds_of(j)[0][0].name
        e = values.get(f"e_{first_bond}")
        e0, e_mean = (float(e[0]), float(e.mean())) if e is not None else (0.0, 0.0)
        p_amb = P_AMBIENT if dom == "pneumatic" and e_mean > 5e4 else 0.0
        dev = max(abs(e_mean - p_amb), E)
        protos.append(dict(kind="leak", constants=[(fresh_name(taken, f"P_amb_{j}"), p_amb, e_unit,
                                                    f"ambient pressure the leak at {j} vents to")],
                           params=[ParamSpec(fresh_name(taken, f"c_leak_{j}"), 0.1 * F / dev, 0.0, 100 * F / dev,
                                             f"({f_unit})/({e_unit})" if e_unit else "",
                                             f"leak conductance at {j}")]))
        chambers = [el for el, _ in junction_elements(graph, j) if el.kind == "PneumaticC" and el.heat is None]
        for chamber in chambers:
            protos.append(_chamber_heat(graph, j, chamber, scales, taken, values))
        if dom in ("pneumatic", "thermal") and not chambers:
            c_unit = DOMAINS[dom].compliance
            c_th = F * scales.span / max(E, 1e-12) * 0.05
            protos.append(dict(kind="heat_transfer", constants=[(fresh_name(taken, f"P_th0_{j}"), e0, e_unit,
                                                                 f"initial pressure of the thermal branch at {j}")],
                               params=[ParamSpec(fresh_name(taken, f"C_th_{j}"), c_th, c_th * 1e-3, c_th * 1e3,
                                                 c_unit, f"thermal compliance at {j}"),
                                       ParamSpec(fresh_name(taken, f"tau_th_{j}"), scales.span / 10,
                                                 scales.dt / 2, scales.span * 10, "s",
                                                 f"thermal time constant at {j}")]))
    for element, _ in junction_elements(graph, j):
        if element.kind != "C":
            continue
        c = element.name
        s_unit = DOMAINS[element.domain].stiffness if element.domain in DOMAINS else ""
        q_unit = DOMAINS[element.domain].displacement if element.domain in DOMAINS else ""
        X = _displacement_scale(values.get(f"state:{element.state}"), scales)
        k_lin = E / X
        protos.append(dict(kind="nonlinear_stiffness", target=c, params=[
            ParamSpec(fresh_name(taken, f"k3_{c}"), 0.0, -100 * k_lin / X ** 2, 100 * k_lin / X ** 2,
                      f"{e_unit}/{q_unit}^3" if q_unit else s_unit, f"cubic stiffness coefficient of {c}"),
            _linear_value(element, taken, k_lin)]))
        if graph.elements[j].kind == "1":
            protos.append(dict(kind="backlash", target=c, params=[
                ParamSpec(fresh_name(taken, f"b_play_{c}"), 0.1 * X, 0.0, 3 * X, q_unit,
                          f"half-width of the play in front of {c}")]))
        q = values.get(f"state:{element.state}")
        if q is not None and np.ptp(q) > 0 and element.state:
            protos.append(_content_limit(graph, j, element, q, k_lin, scales, taken, q_unit))
    return protos


def _chamber_heat(graph, j, chamber, scales, taken, values) -> dict:
    """The ``heat_transfer`` prototype of a pneumatic chamber: its thermal form (gas temperature state),
    with the wall conductance hA (W/K) scaled so that the heat capacity of the gas at the junction's
    mean pressure relaxes in a tenth of the record."""
    params = {n: p.value for n, p in graph.parameters().items()}
    t_wall = float(params.get(chamber.temperature, 293.0))
    e = values.get(f"e_{graph.bonds_of(j)[0][0].name}")
    pressure = float(np.mean(e)) if e is not None else chamber.initial_pressure
    heat_capacity = pressure * _chamber_volume(graph, chamber, params) / (0.4 * t_wall)   # m c_v, J/K
    h_a, gamma = fresh_name(taken, f"hA_{chamber.name}"), fresh_name(taken, f"gamma_{chamber.name}")
    per_second = heat_capacity / scales.span          # hA that relaxes the gas over the whole record
    return dict(kind="heat_transfer", target=chamber.name, constants=[],
                initial={chamber.gas_state: t_wall},
                starts=[{h_a: 100 * per_second, gamma: 1.4}, {h_a: per_second, gamma: 1.4}],
                params=[ParamSpec(h_a, 10 * per_second, 0.01 * per_second, 2 * heat_capacity / scales.dt, "W/K",
                                  f"heat conductance from the gas in {chamber.name} to its wall"),
                        ParamSpec(gamma, 1.4, 1.0, 1.67, "1",
                                  f"ratio of specific heats of the gas in {chamber.name}")])


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


def _linear_value(element, taken, k_lin: float) -> ParamSpec:
    """The C's own linear value, refitted with its cubic term (within a factor 3): its
    stiffness or compliance parameter (named as the element) for a linear C, else a
    linear term ``dk_<C> q`` added to its law (within 3 `k_lin` either way).  A linear model identified from data carries the
    cubic term's average in its linear value, which is wrong once the cubic term is there.
    A zero stiffness (a free mass) may become up to 10 `k_lin`, the junction's effort over
    the C's displacement scale."""
    c = element.name
    if element.value is not None and element.stiffness_form and float(element.value.value) == 0.0:
        return ParamSpec(c, 0.0, 0.0, 10 * k_lin, element.value.unit, f"linear stiffness of {c} (refitted)")
    if element.value is not None and float(element.value.value) > 0:
        v = float(element.value.value)
        quantity = "stiffness" if element.stiffness_form else "compliance"
        return ParamSpec(c, v, v / 3, 3 * v, element.value.unit, f"linear {quantity} of {c} (refitted)")
    unit = DOMAINS[element.domain].stiffness if element.domain in DOMAINS else ""
    return ParamSpec(fresh_name(taken, f"dk_{c}"), 0.0, -3 * k_lin, 3 * k_lin, unit,
                     f"change of the linear stiffness of {c} (refitted)")


def _content_limit(graph, j, element, q, k_lin, scales, taken, q_unit) -> dict:
    """The ``saturation`` prototype of C `element` at junction `j` (its content trajectory `q`)."""
    c = element.name
    lo, hi = float(np.min(q)), float(np.max(q))
    width = hi - lo
    q_max = fresh_name(taken, f"q_max_{c}")
    if graph.elements[j].kind == "0":
        k = fresh_name(taken, f"k_of_{c}")
        return dict(kind="saturation", target=c, regime=element.state,
                    constants=[(k, 1.0 / (5.0 * scales.dt), "1/s", f"overflow rate of {c} beyond its limit")],
                    starts=[{q_max: lo + f * width} for f in (0.95, 0.8, 0.6)],
                    params=[ParamSpec(q_max, hi + 1e-3 * width, lo, hi + width, q_unit,
                                      f"content of {c} beyond which it overflows")])
    q_min, k = fresh_name(taken, f"q_min_{c}"), fresh_name(taken, f"k_stop_{c}")
    return dict(kind="saturation", target=c, regime=element.state,
                constants=[(k, 30.0 * k_lin, DOMAINS[element.domain].stiffness if element.domain in DOMAINS else "",
                            f"stiffness of the end stops of {c}")],
                starts=([{q_min: lo - 1e-3 * width, q_max: lo + f * width} for f in (0.9, 0.7)]
                        + [{q_min: lo + f * width, q_max: hi + 1e-3 * width} for f in (0.1, 0.3)]),
                params=[ParamSpec(q_min, lo - 1e-3 * width, lo - width, hi, q_unit, f"lower end stop of {c}"),
                        ParamSpec(q_max, hi + 1e-3 * width, lo, hi + width, q_unit, f"upper end stop of {c}")])


def _displacement_scale(q, scales) -> float:
    """RMS of a C's displacement in the nominal simulation (the junction's scale without one)."""
    scale = float(np.sqrt(np.mean(q ** 2))) if q is not None else 0.0
    return scale if scale > 0 and np.isfinite(scale) else scales.displacement


def build_storage(data: dict, graph, cand, values: dict) -> None:
    """Add the leak / heat-transfer branch, or change the C's law, in the graph dict `data`."""
    j = cand.place.name
    p = [spec.name for spec in cand.params]
    c = [const[0] for const in cand.constants]
    dom = junction_domain(graph, j)
    if cand.kind == "leak":
        name = f"leak_{j}"
        data["elements"].append({"kind": "R", "name": name, "domain": dom, "flow": f"{p[0]}*(e - {c[0]})",
                                 "description": f"leak from {j} to the ambient"})
        data["bonds"].append({"name": f"b_{name}", "tail": [j, ""], "head": [name, ""]})
        return
    if cand.kind == "saturation":
        name, q = f"limit_{cand.target}", cand.regime
        if graph.elements[j].kind == "0":
            law = {"flow": f"{c[0]}*Max({q} - {p[0]}, 0)"}
        else:
            law = {"effort": f"{c[0]}*(Max({q} - {p[1]}, 0) + Min({q} - {p[0]}, 0))"}
        data["elements"].append({"kind": "R", "name": name, "domain": dom, **law,
                                 "description": f"limits of the content of {cand.target}"})
        data["bonds"].append({"name": f"b_{name}", "tail": [j, ""], "head": [name, ""]})
        return
    if cand.kind == "heat_transfer" and cand.target is not None:   # the chamber's own thermal form
        entry = next(e for e in data["elements"] if e["name"] == cand.target)
        entry["heat"] = {"hA": p[0], "gamma": p[1]}
        entry["initial_temperature"] = float(next(iter(cand.initial.values())))
        entry["description"] = (entry.get("description", "") + " (with wall heat exchange)").strip()
        return
    if cand.kind == "heat_transfer":
        branch, r_th, c_th = f"heat_{j}", f"R_th_{j}", f"C_th_el_{j}"
        data["elements"] += [
            {"kind": "1", "name": branch, "description": f"heat exchange branch of the chamber at {j}"},
            {"kind": "R", "name": r_th, "domain": dom, "flow": f"e*{p[0]}/{p[1]}",
             "description": f"thermal resistance tau_th / C_th at {j}"},
            {"kind": "C", "name": c_th, "domain": dom, "law": f"{c[0]} + q/{p[0]}", "state": f"q_th_{j}",
             "initial": 0.0, "description": f"thermal compliance at {j}"}]
        data["bonds"] += [{"name": f"b_{branch}", "tail": [j, ""], "head": [branch, ""]},
                          {"name": f"b_{r_th}", "tail": [branch, ""], "head": [r_th, ""]},
                          {"name": f"b_{c_th}", "tail": [branch, ""], "head": [c_th, ""]}]
        return
    entry = next(e for e in data["elements"] if e["name"] == cand.target)
    if cand.kind == "nonlinear_stiffness":
        entry["law"] = f"{_refitted_law(entry, p[1])} + {p[0]}*q**3"
    else:  # backlash: the law sees the displacement beyond the play
        law = _c_law(entry)
        dead = f"q - Max(-{p[0]}, Min({p[0]}, q))"
        entry["law"] = substitute(substitute(law, entry.get("state", f"q_{cand.target}"), "q"), "q", dead)
    entry["description"] = (entry.get("description", "") + f" (with {cand.kind.replace('_', ' ')})").strip()


def _refitted_law(entry: dict, linear: str) -> str:
    """The C entry's law in ``q`` with its linear value the graph parameter `linear` (a linear C
    loses its own value, which `linear`, named as the element, replaces), or a law with the
    linear term ``linear*q`` added."""
    for key, form in (("stiffness", f"{linear}*q"), ("value", f"q/{linear}")):
        if key in entry and linear == entry["name"]:
            entry.pop(key)
            entry.pop("unit", None)
            return form
    return f"{_c_law(entry)} + {linear}*q"


def _c_law(entry: dict) -> str:
    """The C entry's law as a string in ``q``; a linear C becomes a law with its parameter kept."""
    name = entry["name"]
    if "law" in entry:
        return f"({entry['law']})"
    for key, form in (("stiffness", f"{name}*q"), ("value", f"q/{name}")):
        if key in entry:
            entry.setdefault("params", {})[name] = {"name": name, "value": entry.pop(key),
                                                    "unit": entry.pop("unit", ""),
                                                    "description": f"{key} of {name}"}
            return form
    raise DiagnosisError(f"C {name!r} has neither a law nor a value")  # pragma: no cover - loader guarantees one


def explain_storage(cand, values: dict, show) -> str:
    """Plain-language sentence for a storage-family candidate."""
    j = cand.place.name
    p = [spec.name for spec in cand.params]
    if cand.kind == "leak":
        return f"the chamber at {j} loses {show(p[0])} of flow per unit of pressure above ambient: a leak at {j}"
    if cand.kind == "heat_transfer" and cand.target is not None:
        return (f"the gas in {cand.target} heats up when compressed or filled and exchanges heat with its "
                f"walls through a conductance of {show(p[0])} (ratio of specific heats {show(p[1])}): "
                f"heat transfer in {cand.target} at {j}")
    if cand.kind == "heat_transfer":
        return (f"the pressure at {j} relaxes with a time constant of {show(p[1])} after each change as the "
                f"gas exchanges heat with its walls (thermal compliance {show(p[0])}): heat transfer at {j}")
    if cand.kind == "saturation" and len(p) == 1:
        return (f"the storage {cand.target} at {j} holds no more than {show(p[0])}: what exceeds it "
                f"overflows (saturation of {cand.target})")
    if cand.kind == "saturation":
        return (f"the content of {cand.target} at {j} stays within {show(p[0])} .. {show(p[1])}: end stops "
                f"(saturation of {cand.target})")
    if cand.kind == "nonlinear_stiffness":
        k3 = values.get(p[0], 0.0)
        word = "stiffens" if k3 > 0 else ("softens" if k3 < 0 else "changes its stiffness")
        linear = next(spec for spec in cand.params if spec.name == p[1])
        was = f"{linear.guess:.3g} {linear.unit if linear.unit != '1' else ''}".strip()
        return (f"the spring {cand.target} at {j} {word} with deflection (cubic term {show(p[0])}; "
                f"{linear.description.replace(' (refitted)', '')} refitted with it: {show(p[1])}, "
                f"nominal {was}): nonlinear stiffness of {cand.target}")
    return (f"the spring {cand.target} at {j} only engages beyond a play of +/- {show(p[0])}: "
            f"backlash in front of {cand.target}")
