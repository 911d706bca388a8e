"""Friction kinds at a 1-junction (common flow v): an R element with a nonlinear law, or a
Dahl hysteresis element.

Laws (``f`` = the junction's flow into the element, ``e`` = its effort):

* ``coulomb_friction``: :math:`e = F_c \\tanh(f / v_\\varepsilon)`.  The smooth
  sign keeps the model smooth (variable-step integration, Model-Exchange
  FMU); :math:`v_\\varepsilon` is fixed (not fitted) at 5 % of the RMS flow of
  the nominal simulation at that junction, so the friction reaches 76 % of its
  level at 5 % of the typical speed.
* ``viscous_friction``: :math:`e = b f`.
* ``stribeck_friction``: :math:`e = (F_c + \\Delta F_s e^{-(f/v_s)^2}) \\tanh(f/v_\\varepsilon)`
  (static level :math:`F_c + \\Delta F_s`; viscous friction is its own kind).
* ``coulomb_viscous_friction``: :math:`e = F_c \\tanh(f / v_\\varepsilon) + b f`, both
  levels fitted together as one law (a lubricated guide or a ball screw has
  both; fitted one at a time, the first absorbs part of the second).
* ``pressure_dependent_friction``: :math:`e = (c_0 + c_1 (P - P_{ref})) \\tanh(f/v_\\varepsilon)`
  with :math:`P` a pressure of the model (a chamber state, a C effort, or
  their mean) and :math:`P_{ref}` its mean in the nominal simulation (fixed),
  so :math:`c_0` is the Coulomb level at the mean pressure.
* ``hysteresis``: Dahl friction [1]_, an equation element with the friction
  effort :math:`z` as state, :math:`\\dot z = \\sigma (f - |f| z / F_h)`: elastic
  (stiffness :math:`\\sigma`) for small reversals, :math:`\\pm F_h` in steady sliding,
  rate-independent hysteresis loops in between.

References
----------
.. [1] P. R. Dahl, "Solid friction damping of mechanical vibrations", AIAA
   Journal 14(12), 1976, eq. (1) with exponent 1.
"""
from __future__ import annotations

from .catalogue_common import ParamSpec, fresh_name, junction_domain, junction_units
from .catalogue_scales import pressure_variables

__all__ = ["FRICTION_KINDS", "make_friction", "build_friction", "explain_friction"]

FRICTION_KINDS = ("coulomb_friction", "viscous_friction", "stribeck_friction", "pressure_dependent_friction",
                  "hysteresis", "coulomb_viscous_friction")

#: smoothing velocity of the sign, as a fraction of the RMS junction flow
V_EPS_FRACTION = 0.05


def make_friction(graph, place, scales, taken, values=None) -> list[dict]:
    """Candidate prototypes (kind, params, constants, regime) for a 1-junction
    (`values`: nominal values at the junction, :func:`~diagnosis.catalogue_scales.junction_scales`)."""
    j = place.name
    e_unit, f_unit = junction_units(graph, j)
    E, V = scales.effort, scales.flow
    b_unit = f"{e_unit} s/m" if f_unit == "m/s" else (f"{e_unit}/({f_unit})" if f_unit else "")
    name = lambda base: fresh_name(taken, f"{base}_{j}")  # noqa: E731 - short local namer
    v_eps = (name("v_eps"), V_EPS_FRACTION * V, f_unit, f"smoothing flow of the friction sign at {j}")
    level = lambda n, what: ParamSpec(name(n), 0.1 * E, 0.0, 10 * E, e_unit, what)  # noqa: E731
    viscous = ParamSpec(name("b_visc"), 0.1 * E / V, 0.0, 100 * E / V, b_unit, f"viscous friction coefficient at {j}")
    protos = [
        dict(kind="coulomb_friction", params=[level("Fc", f"Coulomb friction level at {j}")],
             constants=[v_eps]),
        dict(kind="viscous_friction", params=[viscous]),
        dict(kind="coulomb_viscous_friction", params=[level("Fc", f"Coulomb friction level at {j}"), viscous],
             constants=[v_eps]),
        dict(kind="stribeck_friction", constants=[v_eps], params=[
            level("Fc", f"Coulomb friction level at {j}"),
            level("dFs", f"static friction in excess of the Coulomb level at {j}"),
            ParamSpec(name("v_s"), 0.2 * V, 0.005 * V, 10 * V, f_unit, f"Stribeck velocity at {j}")]),
        dict(kind="hysteresis", params=[
            ParamSpec(name("Fh"), 0.1 * E, 1e-3 * E, 10 * E, e_unit, f"Dahl friction level at {j}"),
            ParamSpec(name("sigma_dahl"), 2.0 * E / scales.displacement, 2e-3 * E / scales.displacement,
                      2e3 * E / scales.displacement, f"{e_unit}/{_displacement_unit(f_unit)}",
                      f"Dahl pre-sliding stiffness at {j}")]),
    ]
    pressures = pressure_variables(graph)
    for label, expr in pressures.items():
        p = (values or {}).get(f"pressure:{label}")
        p_ref = float(p.mean()) if p is not None else 0.0
        p_scale = float(p.std()) if p is not None and p.std() > 0 else max(abs(p_ref), 1.0)
        protos.append(dict(
            kind="pressure_dependent_friction", regime=expr, constants=[
                v_eps, (name("p_ref"), p_ref, "Pa", f"reference pressure of the friction law at {j}")],
            params=[level("c0", f"Coulomb friction level at {j} at the reference pressure"),
                    ParamSpec(name("c1"), 0.0, -10 * E / p_scale, 10 * E / p_scale, f"{e_unit}/Pa",
                              f"change of the friction level at {j} per Pa of {label}")]))
    for proto in protos:   # the friction level may be far from 10 % of the effort scale
        first = proto["params"][0]
        proto["starts"] = [{first.name: f * first.guess} for f in (0.1, 5.0) if f * first.guess <= first.upper]
    return protos


def _displacement_unit(f_unit: str) -> str:
    return {"m/s": "m", "rad/s": "rad", "m^3/s": "m^3", "A": "C", "kg/s": "kg"}.get(f_unit, "1")


def build_friction(data: dict, graph, cand, values: dict) -> None:
    """Attach the friction element of `cand` to its 1-junction in the graph dict `data`."""
    j = cand.place.name
    dom = junction_domain(graph, j)
    p = [spec.name for spec in cand.params]
    c = [const[0] for const in cand.constants]
    sign = f"tanh(f/{c[0]})" if c else ""
    element = f"{cand.kind}_{j}"
    if cand.kind == "hysteresis":
        state = f"F_dahl_{j}"
        entry = {"kind": "Eq", "name": element, "ports": {"m": "in"}, "outputs": {"e_m": state},
                 "states": {state: f"{p[1]}*(f_m - Abs(f_m)*{state}/{p[0]})"}, "initial": {state: 0.0},
                 "units": {state: junction_units(graph, j)[0]},
                 "description": f"Dahl hysteretic friction at {j}"}
        port = "m"
    else:
        if cand.kind == "coulomb_friction":
            law = f"{p[0]}*{sign}"
        elif cand.kind == "viscous_friction":
            law = f"{p[0]}*f"
        elif cand.kind == "coulomb_viscous_friction":
            law = f"{p[0]}*{sign} + {p[1]}*f"
        elif cand.kind == "stribeck_friction":
            law = f"({p[0]} + {p[1]}*exp(-(f/{p[2]})**2))*{sign}"
        else:  # pressure_dependent_friction
            law = f"({p[0]} + {p[1]}*(({cand.regime}) - {c[1]}))*{sign}"
        entry = {"kind": "R", "name": element, "domain": dom, "effort": law,
                 "description": f"{cand.kind.replace('_', ' ')} at {j}"}
        port = ""
    data["elements"].append(entry)
    data["bonds"].append({"name": f"b_{element}", "tail": [j, ""], "head": [element, port]})


def explain_friction(cand, values: dict, show) -> str:
    """Plain-language sentence for a friction candidate (`show(name)` formats a value with its unit)."""
    j = cand.place.name
    p = [spec.name for spec in cand.params]
    if cand.kind == "coulomb_friction":
        return (f"the motion at {j} loses about {show(p[0])} whenever it moves, whatever its speed: "
                f"Coulomb friction at the {j} 1-junction")
    if cand.kind == "viscous_friction":
        return f"the motion at {j} is braked in proportion to its speed ({show(p[0])}): viscous friction at {j}"
    if cand.kind == "coulomb_viscous_friction":
        return (f"the motion at {j} loses about {show(p[0])} whenever it moves plus {show(p[1])} times its "
                f"speed: Coulomb and viscous friction together at the {j} 1-junction")
    if cand.kind == "stribeck_friction":
        return (f"the motion at {j} loses {show(p[0])} when sliding and up to {show(p[1])} more near "
                f"standstill (fading above about {show(p[2])}): Stribeck friction at {j}")
    if cand.kind == "pressure_dependent_friction":
        c1 = values.get(p[1], 0.0)
        trend = (f"{'more' if c1 > 0 else 'less'} at higher {cand.regime} ({show(p[1])})" if c1
                 else f"whatever {cand.regime}")
        p_ref = next(value for name, value, *_ in cand.constants if name.startswith("p_ref"))
        return (f"the motion at {j} loses about {show(p[0])} whenever it moves (at {cand.regime} = "
                f"{p_ref:.4g} Pa), {trend}: pressure-dependent Coulomb friction at the {j} 1-junction")
    return (f"the motion at {j} meets a friction of up to {show(p[0])} that builds up elastically "
            f"({show(p[1])}) after each reversal: hysteretic (Dahl) friction at {j}")
