"""Rerouting an input through an effect: the part of the editing API that works on element
descriptions and expression text.

:meth:`~bondgraph.editing.GraphEditing.route_input` makes every element that reads an input
``u`` read an expression of it instead (an actuator lag, a delay, a saturation), and gives the
effect's extra states to one of those elements.  The elements concerned are of many kinds (sources,
modulated sources with named locals, equation elements), so each is rebuilt from its description
(:meth:`~bondgraph.elements.base.Element.to_dict`) with the input's name replaced, as a whole
word, in its expression fields: the one place where the editing API edits expression text rather
than sympy expressions, since the expressions are parsed only against the finished graph's names.
"""
from __future__ import annotations

import copy as _copy
import dataclasses
import re

from .elements.base import ELEMENT_KINDS, Element
from .errors import GraphError, UnknownNameError

__all__ = ["route_input", "substitute_name", "expression_fields", "mentions", "rebuilt"]

#: keys of an element description holding expressions (strings or maps of strings)
_EXPRESSION_KEYS = ("expression", "effort", "flow", "law", "modulus", "outputs", "states", "held", "locals")


def substitute_name(text: str, name: str, replacement: str) -> str:
    """`text` with the identifier `name` (a whole word, not an attribute) replaced by
    ``(replacement)``."""
    return re.sub(rf"(?<![\w.]){re.escape(name)}(?!\w)", f"({replacement})", text)


def mentions(text: str, name: str) -> bool:
    """Does the expression `text` use the identifier `name`?"""
    return substitute_name(text, name, "") != text


def expression_fields(entry: dict):
    """Yield ``(container, key)`` for every expression string of an element description."""
    for key in _EXPRESSION_KEYS:
        value = entry.get(key)
        if isinstance(value, str):
            yield entry, key
        elif isinstance(value, dict):
            for sub, text in value.items():
                if isinstance(text, str):
                    yield value, sub


def rebuilt(entry: dict) -> Element:
    """The element an element description (``Element.to_dict()``) describes."""
    entry = _copy.deepcopy(entry)
    kind, name = entry.pop("kind"), entry.pop("name")
    return ELEMENT_KINDS[kind](name, **entry)


def route_input(graph, u: str, replacement: str, *, states=None, initial=None, units=None):
    """A copy of `graph` in which every user of input `u` sees `replacement` instead; `u` stays an
    input of the model (:meth:`~bondgraph.editing.GraphEditing.route_input` documents the call).

    Returns ``(graph, carrier)``: the new graph and the name of the element owning the new
    `states` ("" without states).
    """
    decl = next((d for d in graph.inputs() if d.name == u), None)
    if decl is None:
        raise UnknownNameError("input", u, [d.name for d in graph.inputs()], model=graph.name)
    states = dict(states or {})
    new = graph.copy()
    entries = {name: element.to_dict() for name, element in new.elements.items()}
    carrier, users, ported = "", [], set()
    for name, entry in entries.items():
        if entry["kind"] in ("Se", "Sf") and (entry.get("input") or name) == u:
            role = "e" if entry["kind"] == "Se" else "f"
            dom, unit, desc = entry.get("domain", "generic"), entry.get("unit", ""), entry.get("description", "")
            entry.clear()
            if states and not carrier:
                entry.update({"kind": "Eq", "name": name, "ports": {"out": "out"},
                              "outputs": {f"{role}_out": replacement}, "description": desc})
                carrier = name
                ported.add(name)
            else:
                entry.update({"kind": "MSe" if role == "e" else "MSf", "name": name, "expression": replacement,
                              "domain": dom, "unit": unit, "description": desc})
            continue
        fields = list(expression_fields(entry))
        if any(mentions(c[k], u) for c, k in fields):
            users.append(entry)
            for container, key in fields:
                container[key] = substitute_name(container[key], u, replacement)
    if states and not carrier:
        carrier = _adopt_states(users, u)
        ported.add(carrier)
    if states:
        entry = entries[carrier]
        entry.setdefault("states", {}).update(states)
        entry.setdefault("initial", {}).update(initial or {})
        entry.setdefault("units", {}).update(units or {})
    new.elements = {name: rebuilt(entry) for name, entry in entries.items()}
    new.bonds = {n: dataclasses.replace(b, tail=_out_port(b.tail, ported), head=_out_port(b.head, ported))
                 for n, b in new.bonds.items()}
    if not any(d.name == u for d in new.inputs()):
        new.add_input(u, default=decl.default if decl.function is None else 0.0, unit=decl.unit,
                      description=decl.description)
    new._changed()
    return new, carrier


def _out_port(port, ported: set):
    """A one-port source turned equation element: its bond now ends at port ``out``."""
    return dataclasses.replace(port, port="out") if port.element in ported and port.port == "" else port


def _adopt_states(users: list[dict], u: str) -> str:
    """Give the new states to the first modulated source or equation element using `u`."""
    for entry in users:
        if entry["kind"] == "Eq":
            return entry["name"]
        if entry["kind"] in ("MSe", "MSf"):
            name, role = entry["name"], "e" if entry["kind"] == "MSe" else "f"
            expression, desc = entry["expression"], entry.get("description", "")
            named, params = entry.get("locals"), entry.get("params")
            entry.clear()
            entry.update({"kind": "Eq", "name": name, "ports": {"out": "out"},
                          "outputs": {f"{role}_out": expression}, "description": desc})
            if named:
                entry["locals"] = named
            if params:      # the source's own parameters (a heater's alpha in alpha*Q) go with it
                entry["params"] = params
            return name
    raise GraphError(f"input {u!r} feeds no source, modulated source or equation element that could "
                     "carry the extra state(s)")
