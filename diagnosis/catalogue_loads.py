"""A constant load at a junction: ``constant_load``.

A force offset, a gravity-like load on a lifted axis, a preload, a pump's
constant bypass flow: an effort that does not depend on the motion (at a
1-junction) or a flow that does not depend on the pressure (at a
0-junction).  Built as an R whose law is a constant (``e = F_0`` in
resistance causality at a 1-junction, ``f = Q_0`` in conductance causality
at a 0-junction), so it saves, derives and exports like any element; with
the power convention of an R the load *takes* ``F_0 v`` (``Q_0 e``) from the
junction, and either sign is fitted.
"""
from __future__ import annotations

from .catalogue_common import ParamSpec, fresh_name, junction_domain, junction_units

__all__ = ["LOAD_KINDS", "make_load", "build_load", "explain_load"]

LOAD_KINDS = ("constant_load",)


def make_load(graph, place, scales, taken) -> list[dict]:
    """The constant-load prototype for a 0- or 1-junction, its bounds from the junction's scales."""
    j = place.name
    e_unit, f_unit = junction_units(graph, j)
    one = graph.elements[j].kind == "1"
    size, unit = (scales.effort, e_unit) if one else (scales.flow, f_unit)
    what = "effort" if one else "flow"
    spec = ParamSpec(fresh_name(taken, f"{'F0' if one else 'Q0'}_{j}"), 0.0, -10 * size, 10 * size, unit,
                     f"constant {what} taken from {j}")
    return [dict(kind="constant_load", params=[spec],
                 starts=[{spec.name: s * 0.1 * size} for s in (1.0, -1.0)])]


def build_load(data: dict, graph, cand, values: dict) -> None:
    """Attach the constant-law R of `cand` to its junction in the graph dict `data`."""
    j = cand.place.name
    name = f"constant_load_{j}"
    law = {"effort": cand.params[0].name} if graph.elements[j].kind == "1" else {"flow": cand.params[0].name}
    data["elements"].append({"kind": "R", "name": name, "domain": junction_domain(graph, j), **law,
                             "description": f"constant load at {j}"})
    data["bonds"].append({"name": f"b_{name}", "tail": [j, ""], "head": [name, ""]})


def explain_load(cand, values: dict, show) -> str:
    """Plain-language sentence for a constant load."""
    j = cand.place.name
    p = cand.params[0].name
    what = "effort" if p.startswith("F0") else "flow"
    return (f"a constant {what} of {show(p)} is taken from {j} whatever the motion (an offset, a preload or "
            f"a gravity-like load): a constant load at {j}")
