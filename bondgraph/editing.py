"""The editing API of :class:`~bondgraph.graph.BondGraph`: each call returns a new graph.

:meth:`~GraphEditing.copy`, :meth:`~GraphEditing.with_params`, :meth:`~GraphEditing.insert`
(a one-port element, or a new junction, bonded to a junction), :meth:`~GraphEditing.insert_on_bond`
(a junction or a two-port put into a bond), :meth:`~GraphEditing.replace` (an element swapped, its
bonds kept), :meth:`~GraphEditing.remove` (an element and its bonds, or a bond),
:meth:`~GraphEditing.declare` (graph-wide parameters added), :meth:`~GraphEditing.with_law` (a
storage element's law rewritten as a sympy expression), :meth:`~GraphEditing.with_output` (an
output's expression rewritten), :meth:`~GraphEditing.with_outputs` (the outputs replaced),
:meth:`~GraphEditing.with_element` (an element rebuilt from its
description with some fields changed), :meth:`~GraphEditing.route_input` (every user of an
input made to read an expression of it, :mod:`bondgraph.editing_inputs`) and
:meth:`~GraphEditing.sense_output` (an output read through a sensor's own dynamics).  The graph they
are called on is never changed, so a model and its variants (the diagnosis catalogue's
candidates, a sweep's plants) can live side by side.

>>> from bondgraph import BondGraph, C, I, One, R, Se
>>> g = BondGraph("msd")
>>> for e in (Se("F"), One("v"), I("m", 2.0), C("c", 0.5), R("b", 0.4)):
...     _ = g.add(e)
>>> for e in ("m", "c", "b"):
...     _ = g.connect("v", e)
>>> _ = g.connect("F", "v")
>>> stiffer = g.with_params(c=0.25)
>>> stiffer.parameters()["c"].value, g.parameters()["c"].value
(0.25, 0.5)
>>> print(g.insert(R("b2", 0.1), at="v").equations().f[0])
F - b*p_m/m - b2*p_m/m - q_c/c
"""
from __future__ import annotations

import copy as _copy
import dataclasses
from collections.abc import Mapping

import sympy as sp

from .editing_delays import delay_input, with_delays_realised
from .editing_inputs import mentions, rebuilt, route_input
from .elements import Element
from .errors import GraphError, PortError, UnknownNameError
from .params import Param
from .symbols import as_expression

__all__ = ["GraphEditing"]


class GraphEditing:
    """Editing methods mixed into :class:`~bondgraph.graph.BondGraph` (each returns a new graph)."""

    def copy(self, name: str | None = None, *, description: str | None = None):
        """An independent copy (elements, bonds, declarations), optionally renamed to `name` and
        described by `description`."""
        # derived equations are not copied; sympy expressions are immutable, so the copy shares
        # them (rebuilding them made a copy of pam take 0.12 s instead of 0.01 s)
        new = _copy.deepcopy(self, _sympy_shared(self, {id(self._cache): None}))
        if name is not None:
            if not isinstance(name, str) or not name.isidentifier():
                raise GraphError(f"graph name {name!r} is not a valid identifier")
            new.name = name
        if description is not None:
            new.description = str(description)
        new._changed()
        return new

    def with_params(self, values: Mapping[str, float] | None = None, /, **more: float):
        """A copy whose parameters `values` (and `more`) have new values, SI as declared.

        Every element sharing a parameter name gets the new value.  An unknown name is an
        :class:`UnknownNameError` listing the graph's parameters; a value outside the
        parameter's range a :class:`ParameterError`.
        """
        changes = {**dict(values or {}), **more}
        known = self.parameters()
        for key in changes:
            if key not in known:
                raise UnknownNameError("parameter", key, known, model=self.name)
        new = self.copy()
        replaced = {key: dataclasses.replace(known[key], value=value) for key, value in changes.items()}
        for element in new.elements.values():
            _swap_params(vars(element), replaced)
        _swap_params(new.extra_params, replaced)
        new._changed()
        return new

    def insert(self, element: Element, *, at: str, bond: str | None = None):
        """A copy with `element` added and bonded to junction `at`.

        `element` has one port (a one-port, or an equation element with a single named port) or
        is a new junction (bonded from `at`, so that more elements can hang on it).  The bond's
        half-arrow follows the element's natural direction: into a storage, resistor or junction,
        out of a source.  `bond` names the new bond (default ``bondN``).
        """
        self._junction(at)
        if element.ports is not None and len(element.ports) != 1:
            raise PortError(f"insert() bonds one-port elements; {element.kind} {element.name!r} has ports "
                            f"{', '.join(map(repr, element.ports or ()))}: use add() and connect()",
                            element=element.name)
        port = "" if element.ports is None else element.ports[0]
        end = (element.name, port) if port else element.name
        new = self.copy()
        new.add(element)
        if element.direction(port) == "in":
            new.connect(at, end, name=bond)
        else:
            new.connect(end, at, name=bond)
        return new

    def insert_on_bond(self, bond: str, element: Element, *, name: str | None = None):
        """A copy with `element` (a junction, or a two-port: TF, GY, MTF, MGY) put into `bond`.

        ``tail -> head`` becomes ``tail -> element -> head``: the first half keeps the name
        `bond` (so ``e_<bond>``, ``f_<bond>`` still name the tail side), the second is `name`
        (default ``<bond>_<element>``).  A two-port takes the tail on port ``"1"`` and gives
        the head from port ``"2"``.
        """
        old = self._bond(bond)
        if element.ports is None:
            middle_in, middle_out = element.name, element.name
        elif tuple(element.ports) == ("1", "2"):
            middle_in, middle_out = (element.name, "1"), (element.name, "2")
        else:
            raise PortError(f"insert_on_bond() takes a junction or a two-port; {element.kind} {element.name!r} "
                            f"has ports {', '.join(map(repr, element.ports))}", element=element.name)
        new = self.copy()
        order = list(new.bonds)
        del new.bonds[bond]
        new.add(element)
        first = new.connect(_end(old.tail), middle_in, name=bond)
        second = new.connect(middle_out, _end(old.head), name=name or f"{bond}_{element.name}")
        at = order.index(bond)
        names = order[:at] + [first.name, second.name] + order[at + 1:]
        new.bonds = {n: new.bonds[n] for n in names}
        new._changed()
        return new

    def replace(self, name: str, element: Element):
        """A copy with element `name` replaced by `element`, which keeps its bonds.

        `element` must have the same ports (both junctions, or the same port names); it may
        have another name, and the bonds follow it.
        """
        old = self._element(name)
        if (old.ports is None) != (element.ports is None) or (
                old.ports is not None and tuple(old.ports) != tuple(element.ports)):
            raise PortError(f"{_kind(element)} {element.name!r} cannot replace {_kind(old)} {name!r}: ports "
                            f"{_ports(element)} instead of {_ports(old)}", element=element.name)
        if element.name != name and (element.name in self.elements or element.name in self.bonds):
            raise GraphError(f"cannot replace {name!r} by {element.name!r}: the graph already has that name")
        new = self.copy()
        new.elements = {(element.name if n == name else n): (element if n == name else e)
                        for n, e in new.elements.items()}
        new.bonds = {n: dataclasses.replace(b, tail=_renamed(b.tail, name, element.name),
                                            head=_renamed(b.head, name, element.name))
                     for n, b in new.bonds.items()}
        new._changed()
        return new

    def declare(self, *params: Param):
        """A copy with the graph-wide parameters `params` declared (each a :class:`Param`); a name
        the graph already has is a :class:`DuplicateNameError`."""
        new = self.copy()
        for param in params:
            new.add_parameter(param)
        return new

    def with_law(self, name: str, law, *, description: str | None = None):
        """A copy whose storage element `name` (an I or a C) has the constitutive law `law`.

        `law` is an expression in the element's local energy variable (``q`` for a C, ``p`` for
        an I: a string or a sympy expression), or a callable ``law(old, x)`` given the present law
        as a sympy expression in ``x``, the local variable's symbol, returning the new one.  A
        linear element's law is ``x/value`` (``value*x`` in stiffness form); its value stays a
        parameter of the element as long as the new law uses it.  State, initial value, domain and
        the law's other parameters are kept, and the description unless `description` is given.

        >>> from bondgraph import BondGraph, C, I, One, Se
        >>> g = BondGraph("spring")
        >>> for e in (Se("F"), One("v"), I("m", 1.0), C("k", stiffness=4.0)):
        ...     _ = g.add(e)
        >>> for a, b in (("F", "v"), ("v", "m"), ("v", "k")):
        ...     _ = g.connect(a, b)
        >>> hard = g.with_law("k", lambda old, q: old + sp.Symbol("k3") * q**3).declare(Param("k3", 0.5))
        >>> print(hard.equations().f[0])
        F - k*q_k - k3*q_k**3
        """
        old = self._element(name)
        if old.kind not in ("I", "C"):
            raise GraphError(f"with_law() rewrites the law of an I or a C; {_kind(old)} {name!r} is neither")
        x = sp.Symbol(old._local)
        if old.value is not None:
            own = old.value.name
            current = (sp.Symbol(own) * x if getattr(old, "stiffness_form", False) else x / sp.Symbol(own))
        else:
            table = {n: sp.Symbol(n) for n in self.names()}
            table[old.state] = table[old._local] = x
            current = as_expression(old.law, table, owner=f"{old.kind} {name!r} law")
        new_law = law(current, x) if callable(law) else law
        params = {k: p for k, p in old.params.items() if p is not old.value}
        if old.value is not None and (mentions(new_law, old.value.name) if isinstance(new_law, str) else
                                      old.value.name in {s.name for s in sp.sympify(new_law).free_symbols}):
            params[old.value.name] = old.value
        element = type(old)(name, law=new_law, params=params, state=old.state, initial=old.initial,
                            domain=old.domain, description=old.description if description is None else description)
        return self.replace(name, element)

    def with_output(self, name: str, expression):
        """A copy whose output `name` has the expression `expression` (unit and description kept).

        `expression` is a string or sympy expression, or a callable given the present expression
        as a sympy expression (every name of the graph a plain symbol of that name) and returning
        the new one, e.g. ``lambda y: y + sp.Symbol("offset")``.
        """
        if name not in self.outputs:
            raise UnknownNameError("output", name, self.outputs, model=self.name)
        out = self.outputs[name]
        if callable(expression):
            table = {n: sp.Symbol(n) for n in self.names()}
            expression = expression(as_expression(out.expression, table, owner=f"output {name!r}"))
        new = self.copy()
        new.outputs[name] = dataclasses.replace(out, expression=str(expression))
        new._changed()
        return new

    def with_outputs(self, outputs: Mapping[str, object]):
        """A copy whose outputs are exactly `outputs`: name -> expression (a string or sympy
        expression), or name -> ``(expression, unit)``; the graph's own outputs are dropped."""
        new = self.copy()
        new.outputs = {}
        for name, spec in outputs.items():
            expression, unit = spec if isinstance(spec, tuple) else (spec, "")
            new.add_output(name, expression, unit=unit)
        return new

    def sense_output(self, name: str, states: Mapping[str, object], reads, *, initial=None, units=None,
                     element: str | None = None, description: str = ""):
        """A copy whose output `name` is read through a sensor with dynamics of its own.

        `states` maps each new state to its rate, and `reads` is what the output reads; each is a
        string or sympy expression, or a callable given the output's present expression (a sympy
        expression, every name of the graph a plain symbol of that name) and returning one.  A
        first-order sensor lag::

            lag = g.sense_output("T", {"T_s": lambda y: (y - sp.Symbol("T_s")) / sp.Symbol("tau")}, "T_s",
                                 initial={"T_s": 296.15}, units={"T_s": "K"})

        The states belong to a new equation element without ports, `element` (default
        ``sensor_<name>``), with their `initial` values and `units`; the parameters the
        expressions use are declared as usual (:meth:`declare`).  Unit and description of the
        output are kept.
        """
        from .elements import EquationElement
        if name not in self.outputs:
            raise UnknownNameError("output", name, self.outputs, model=self.name)
        table = {n: sp.Symbol(n) for n in self.names()}
        present = as_expression(self.outputs[name].expression, table, owner=f"output {name!r}")

        def text(value):
            return str(value(present) if callable(value) else value)

        new = self.copy()
        new.add(EquationElement(element or f"sensor_{name}", ports={}, outputs={},
                                states={s: text(rate) for s, rate in states.items()}, initial=initial, units=units,
                                description=description or f"dynamics of the {name} sensor"))
        new.outputs[name] = dataclasses.replace(new.outputs[name], expression=text(reads))
        new._changed()
        return new

    def with_element(self, name: str, **changes):
        """A copy whose element `name` is rebuilt from its description
        (:meth:`~bondgraph.elements.base.Element.to_dict`, the keywords of its constructor) with
        the fields `changes` replaced, e.g. ``with_element("chamber", heat={...})``."""
        old = self._element(name)
        entry = old.to_dict()
        entry.update(changes)
        return self.replace(name, rebuilt(entry))

    def route_input(self, u: str, replacement: str, *, states: Mapping[str, str] | None = None,
                    initial: Mapping[str, float] | None = None, units: Mapping[str, str] | None = None):
        """A copy in which every element reading input `u` reads the expression `replacement`.

        `u` stays an input of the model (declared on the graph if no element declares it any
        more).  A source whose input is `u` becomes a modulated source of `replacement`; an
        element whose expressions name `u` gets `replacement` in their place.  `states` (name ->
        rate expression, with their `initial` values and `units`) are new states the replacement
        uses; they are owned by the source reading `u` (turned into an equation element with port
        ``out``), else by the first modulated source or equation element using `u`.
        :mod:`bondgraph.editing_inputs` does the work on the elements' descriptions.
        """
        return route_input(self, u, replacement, states=states, initial=initial, units=units)[0]

    def delay_input(self, u: str, time: str, value: float, *, before=None, name: str | None = None):
        """A copy in which every element reading input `u` reads it `value` seconds late.

        The elements read a new delayed input `name` (default ``<u>_late``),
        ``u(t - time)``, with `time` a new parameter (s, >= 0); `u` stays the input a run binds.
        Simulators realise the delay exactly on the recorded samples
        (:mod:`bondgraph.numerics.input_delays`); :meth:`with_delays_realised` turns it into
        states for an FMU.  `before`: the value while ``t - time`` precedes the run, a number or a
        :class:`~bondgraph.params.Param` (a new parameter holding it, which a fit can change like
        `time`); default `u`'s value at the start of the run.  :mod:`bondgraph.editing_delays`
        does the work.
        """
        return delay_input(self, u, time, value, before=before, name=name)

    def with_delays_realised(self):
        """A copy in which every delayed input (:meth:`delay_input`) is three Pade [2/3] states
        (:mod:`bondgraph.editing_delays`): what an FMU, which cannot delay a signal, exports."""
        return with_delays_realised(self)

    def remove(self, name: str):
        """A copy without element `name` and its bonds, or without bond `name`."""
        new = self.copy()
        if name in self.bonds:
            del new.bonds[name]
        else:
            self._element(name)
            del new.elements[name]
            new.bonds = {n: b for n, b in new.bonds.items() if name not in (b.tail.element, b.head.element)}
        new._changed()
        return new

    # -- lookups naming what exists ----------------------------------------
    def _element(self, name: str) -> Element:
        if name not in self.elements:
            raise UnknownNameError("element", name, self.elements, model=self.name)
        return self.elements[name]

    def _junction(self, name: str) -> Element:
        element = self._element(name)
        if element.ports is not None:
            junctions = [n for n, e in self.elements.items() if e.ports is None]
            raise GraphError(f"{_kind(element)} {name!r} is not a junction; the junctions are "
                             f"{', '.join(junctions) or '(none)'}")
        return element

    def _bond(self, name: str):
        if name not in self.bonds:
            raise UnknownNameError("bond", name, self.bonds, model=self.name)
        return self.bonds[name]


def _sympy_shared(root, memo: dict) -> dict:
    """`memo` for :func:`copy.deepcopy` of `root` with every sympy object reachable from it
    mapped to itself (shared, not copied): through dicts, lists, tuples, sets and instance
    dicts, never into the sympy objects themselves."""
    stack, seen = [root], set()
    while stack:
        x = stack.pop()
        if id(x) in seen or id(x) in memo:
            continue
        seen.add(id(x))
        if isinstance(x, sp.Basic):
            memo[id(x)] = x
        elif isinstance(x, dict):
            stack.extend(x.keys())
            stack.extend(x.values())
        elif isinstance(x, (list, tuple, set, frozenset)):
            stack.extend(x)
        elif hasattr(x, "__dict__") and not isinstance(x, type):
            stack.extend(vars(x).values())
    return memo


def _swap_params(container, replaced: dict[str, Param]) -> None:
    """Replace, in place, every Param named in `replaced` inside `container` (a dict, list or
    the attributes of an element), however deep: elements keep a parameter both in ``params``
    and as an attribute (``value``, the modulus)."""
    items = container.items() if isinstance(container, dict) else enumerate(container)
    for key, item in list(items):
        if isinstance(item, Param) and item.name in replaced:
            container[key] = replaced[item.name]
        elif isinstance(item, (dict, list)):
            _swap_params(item, replaced)


def _end(port):
    return (port.element, port.port) if port.port else port.element


def _renamed(port, old: str, new: str):
    return dataclasses.replace(port, element=new) if port.element == old else port


def _kind(element: Element) -> str:
    return f"{element.kind}-junction" if element.ports is None else element.kind


def _ports(element: Element) -> str:
    if element.ports is None:
        return "(any number: a junction)"
    return "(one port)" if tuple(element.ports) == ("",) else ", ".join(map(repr, element.ports))
