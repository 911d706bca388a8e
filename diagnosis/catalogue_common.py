"""Shared pieces of the candidate catalogue: parameter specs and graph-dict surgery.

Every candidate is built by editing the JSON description of the nominal graph
(:func:`bondgraph.io_json.graph_to_dict`) and loading it back, so the result is
a new, ordinary :class:`~bondgraph.BondGraph` that saves, derives and exports
like any other.  Candidate parameters become graph-wide parameters
(``data["parameters"]``), so a compiled candidate model can be re-run with new
values without being rebuilt.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass

from bondgraph.params import DOMAINS

from .errors import DiagnosisError

__all__ = ["ParamSpec", "add_parameter", "fresh_name", "substitute", "junction_elements",
           "junction_domain", "junction_units", "domain_units", "route_input", "expression_fields"]


@dataclass(frozen=True)
class ParamSpec:
    """A fitted parameter of a candidate.

    Parameters
    ----------
    name : str
        Graph parameter name (unique in the candidate graph).
    guess : float
        Starting value, in `unit`.
    lower, upper : float
        Bounds, in `unit` (``lower <= guess <= upper``).
    unit : str
        SI unit.
    description : str
        What it is, in words.
    """

    name: str
    guess: float
    lower: float
    upper: float
    unit: str
    description: str

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name.isidentifier():
            raise DiagnosisError(f"parameter name {self.name!r} is not a valid identifier")
        values = (self.guess, self.lower, self.upper)
        if not all(isinstance(v, (int, float)) and math.isfinite(v) for v in values):
            raise DiagnosisError(f"parameter {self.name!r}: guess and bounds must be finite numbers, "
                                 f"got guess={self.guess!r}, lower={self.lower!r}, upper={self.upper!r}")
        if not self.lower <= self.guess <= self.upper or self.lower == self.upper:
            raise DiagnosisError(f"parameter {self.name!r}: need lower < upper and lower <= guess <= upper, "
                                 f"got {self.lower} <= {self.guess} <= {self.upper} {self.unit}")


def fresh_name(taken, base: str) -> str:
    """`base`, or `base_2`, `base_3`... whichever is not in `taken`."""
    if base not in taken:
        return base
    k = 2
    while f"{base}_{k}" in taken:
        k += 1
    return f"{base}_{k}"


def add_parameter(data: dict, name: str, value: float, unit: str, description: str) -> None:
    """Declare a graph-wide parameter in the graph dict `data`."""
    data.setdefault("parameters", []).append(
        {"name": name, "value": float(value), "unit": unit, "description": description})


def substitute(text: str, name: str, replacement: str) -> str:
    """Replace the identifier `name` (whole word, not an attribute) in an expression string."""
    return re.sub(rf"(?<![\w.]){re.escape(name)}(?!\w)", f"({replacement})", text)


#: keys of an element entry holding expressions (strings or maps of strings)
_EXPRESSION_KEYS = ("expression", "effort", "flow", "law", "modulus", "outputs", "states", "held", "locals")


def expression_fields(entry: dict):
    """Yield ``(container, key)`` for every expression string of an element entry."""
    for key in _EXPRESSION_KEYS:
        value = entry.get(key)
        if isinstance(value, str):
            yield entry, key
        elif isinstance(value, dict):
            for sub, text in value.items():
                if isinstance(text, str):
                    yield value, sub


def junction_elements(graph, junction: str) -> list[tuple[object, object]]:
    """(element, bond) pairs of the elements bonded to `junction`."""
    out = []
    for bond, end in graph.bonds_of(junction):
        other = bond.head.element if end == "tail" else bond.tail.element
        out.append((graph.elements[other], bond))
    return out


def junction_domain(graph, junction: str) -> str:
    """Energy domain of a junction, from the one-ports bonded to it ("generic" if none says)."""
    for element, _ in junction_elements(graph, junction):
        dom = getattr(element, "domain", None)
        if dom in DOMAINS and dom != "generic":
            return dom
    return "generic"


def domain_units(dom: str) -> tuple[str, str]:
    """(effort unit, flow unit) of a domain."""
    d = DOMAINS[dom]
    return d.effort, d.flow


def junction_units(graph, junction: str) -> tuple[str, str]:
    """(effort unit, flow unit) at a junction: its domain's, else those of outputs that read
    one of its bonds' effort / flow (``e_<bond>``, ``f_<bond>``), else ("", "")."""
    effort, flow = domain_units(junction_domain(graph, junction))
    bonds = {b.name for b, _ in graph.bonds_of(junction)}
    for out in graph.outputs.values():
        text = str(out.expression).strip()
        if not effort and text.startswith("e_") and text[2:] in bonds:
            effort = out.unit
        if not flow and text.startswith("f_") and text[2:] in bonds:
            flow = out.unit
    return effort, flow


def _source_input(entry: dict) -> str | None:
    if entry.get("kind") in ("Se", "Sf"):
        return entry.get("input") or entry["name"]
    return None


def route_input(data: dict, graph, u: str, replacement: str, *, states=None, initial=None,
                units=None) -> str:
    """Make every user of input `u` see `replacement` instead, keeping `u` the model's input.

    Parameters
    ----------
    data : dict
        Graph dict, edited in place.
    graph : BondGraph
        The graph `data` describes (for the input's declaration).
    u : str
        Input name.
    replacement : str
        Expression standing for the effective input (may use `u` and `states`).
    states : dict str -> str, optional
        New states and their rates; they are owned by a *carrier*: the source
        that reads `u` (turned into an equation element with port ``out``), or
        the first modulated source / equation element whose expressions use `u`.
    initial, units : dict, optional
        Initial values and units of the new states.

    Returns
    -------
    str
        Name of the carrier element ("" when `states` is empty).
    """
    decl = next((d for d in graph.inputs() if d.name == u), None)
    if decl is None:
        raise DiagnosisError(f"model {graph.name!r} has no input {u!r}; its inputs are "
                             f"{', '.join(d.name for d in graph.inputs()) or '(none)'}")
    states = dict(states or {})
    carrier = ""
    users = []
    for entry in data["elements"]:
        if _source_input(entry) == u:
            role = "e" if entry["kind"] == "Se" else "f"
            name, dom, unit = entry["name"], entry.get("domain", "generic"), entry.get("unit", "")
            desc = entry.get("description", "")
            entry.clear()
            if states and not carrier:
                entry.update({"kind": "Eq", "name": name, "ports": {"out": "out"},
                              "outputs": {f"{role}_out": replacement}, "description": desc})
                carrier = name
                _rename_port(data, name)
            else:
                kind = "MSe" if role == "e" else "MSf"
                entry.update({"kind": kind, "name": name, "expression": replacement, "domain": dom,
                              "unit": unit, "description": desc})
            continue
        fields = list(expression_fields(entry))
        if any(substitute(c[k], u, "") != c[k] for c, k in fields):
            users.append(entry)
            for container, key in fields:
                container[key] = substitute(container[key], u, replacement)
    if not any(_declared(data, u)):
        default = decl.default if decl.function is None else 0.0
        data.setdefault("inputs", []).append({"name": u, "default": float(default), "unit": decl.unit,
                                              "description": decl.description})
    if states and not carrier:
        carrier = _adopt_states(data, users, u)
    if states:
        entry = next(e for e in data["elements"] if e["name"] == carrier)
        entry.setdefault("states", {}).update(states)
        entry.setdefault("initial", {}).update(initial or {})
        entry.setdefault("units", {}).update(units or {})
    return carrier


def _rename_port(data: dict, name: str) -> None:
    """A one-port source turned equation element: its bond now ends at port ``out``."""
    for bond in data["bonds"]:
        for end in ("tail", "head"):
            if bond[end][0] == name:
                bond[end] = [name, "out"]


def _declared(data, u):
    return (d["name"] == u for d in data.get("inputs", []))


def _adopt_states(data: dict, users: list[dict], u: str) -> str:
    """Give the new states to the first modulated source or equation element using `u`."""
    for entry in users:
        if entry["kind"] == "Eq":
            return entry["name"]
        if entry["kind"] in ("MSe", "MSf"):
            name, role = entry["name"], "e" if entry["kind"] == "MSe" else "f"
            expression, desc = entry["expression"], entry.get("description", "")
            named = entry.get("locals")
            entry.clear()
            entry.update({"kind": "Eq", "name": name, "ports": {"out": "out"},
                          "outputs": {f"{role}_out": expression}, "description": desc})
            if named:
                entry["locals"] = named
            _rename_port(data, name)
            return name
    raise DiagnosisError(f"input {u!r} feeds no source, modulated source or equation element that could "
                         "carry the extra state(s); an actuator lag or delay cannot be attached to it")
