"""The bond graph: elements joined by bonds.

A :class:`Bond` is an immutable value ``Bond(name, tail, head)``: power is
positive when it flows from the `tail` port to the `head` port (the half
arrow points at the head).  Each bond carries an effort ``e_<bond>`` and a
flow ``f_<bond>``.
"""
from __future__ import annotations

from dataclasses import dataclass
import sympy as sp

from .editing import GraphEditing
from .elements import Element
from .elements.base import InputDecl, InputDelay
from .errors import DuplicateNameError, ExpressionError, GraphError, JunctionError, PortError
from .guards import Guard
from .params import Param
from .symbols import STEP, TIME, sym

__all__ = ["BondGraph", "Bond", "Port", "Output"]


@dataclass(frozen=True)
class Port:
    """One end of a bond: an element and one of its ports (``""`` for one-ports and junctions)."""

    element: str
    port: str = ""

    def __str__(self) -> str:
        return f"{self.element}.{self.port}" if self.port else self.element


@dataclass(frozen=True)
class Bond:
    """A bond; power is positive from `tail` to `head`."""

    name: str
    tail: Port
    head: Port

    def __str__(self) -> str:
        return f"{self.name}: {self.tail} -> {self.head}"


@dataclass(frozen=True)
class Output:
    """A named output: any expression of states, inputs, parameters and bond variables."""

    name: str
    expression: object
    unit: str = ""
    description: str = ""


class BondGraph(GraphEditing):
    """A bond graph: elements, bonds, declared inputs/parameters and outputs.

    Parameters
    ----------
    name : str
        Model name (an identifier: it names FMUs and generated code).
    description : str
        One line for listings.

    Each editing call (:meth:`copy`, :meth:`with_params`, :meth:`insert`,
    :meth:`insert_on_bond`, :meth:`replace`, :meth:`remove`; :mod:`bondgraph.editing`)
    returns a new graph and leaves this one as it is.

    Examples
    --------
    >>> from bondgraph import BondGraph, Se, I, R, One
    >>> g = BondGraph("damped_mass")
    >>> for e in (Se("F"), One("j"), I("m", 2.0), R("b", 0.5)):
    ...     _ = g.add(e)
    >>> _ = g.connect("F", "j"); _ = g.connect("j", "m"); _ = g.connect("j", "b")
    >>> print(g.equations().f[0])
    F - b*p_m/m
    """

    def __init__(self, name: str = "model", *, description: str = ""):
        if not isinstance(name, str) or not name.isidentifier():
            raise GraphError(f"graph name {name!r} is not a valid identifier")
        self.name = name
        self.description = description
        self.elements: dict[str, Element] = {}
        self.bonds: dict[str, Bond] = {}
        self.outputs: dict[str, Output] = {}
        self.extra_inputs: dict[str, InputDecl] = {}
        self.extra_params: dict[str, Param] = {}
        self.operating_point: dict[str, float] = {}
        self.extra_guards: dict[str, Guard] = {}
        self._version = 0
        self._cache: tuple[int, object] | None = None

    # -- building ------------------------------------------------------------
    def _changed(self):
        self._version += 1
        self._cache = None

    def add(self, element: Element) -> Element:
        """Add `element` and return it; a name already used raises DuplicateNameError."""
        if not isinstance(element, Element):
            raise GraphError(f"expected a bond-graph element, got {element!r}")
        if element.name in self.elements:
            raise DuplicateNameError(element.name, f"graph {self.name!r} already has an element of that name "
                                                   f"({self.elements[element.name].kind})")
        if element.name in self.bonds:
            raise DuplicateNameError(element.name, "a bond already has that name")
        self.elements[element.name] = element
        self._changed()
        return element

    def add_input(self, name: str, *, default: float = 0.0, unit: str = "", description: str = "",
                  delay_of: str | None = None, delay: str | None = None, before: float | str | None = None):
        """Declare an input used by modulated elements (sources declare their own).

        With `delay_of` (another input's name) and `delay` (a parameter's name, s), the input is
        that input late, ``delay_of(t - delay)``, and `before` while ``t - delay`` precedes the
        run: a number, a parameter's name, or by default the source's value at the start
        (:class:`~bondgraph.elements.base.InputDelay`; the names are checked when the equations
        are derived, :meth:`equations`).  A run binds only the source: simulators delay its
        values themselves.
        """
        if not isinstance(name, str) or not name.isidentifier():
            raise GraphError(f"input name {name!r} is not a valid identifier")
        if name in self.extra_inputs:
            raise DuplicateNameError(name, "input declared twice")
        if (delay_of is None) != (delay is None):
            raise GraphError(f"input {name!r}: a delayed input needs both delay_of (the input it "
                             f"delays) and delay (the parameter naming the delay); found "
                             f"delay_of={delay_of!r}, delay={delay!r}")
        default = Param(name, default).value  # a finite number, or a ParameterError naming the input
        late = None
        if delay_of is not None:
            for label, value in (("delay_of", delay_of), ("delay", delay)):
                if not isinstance(value, str) or not value.isidentifier():
                    raise GraphError(f"input {name!r}: {label} {value!r} is not a valid identifier")
            if isinstance(before, str) and not before.isidentifier():
                raise GraphError(f"input {name!r}: before {before!r} is neither a number nor a parameter's name")
            late = InputDelay(delay_of, delay, before if before is None or isinstance(before, str)
                              else Param(name, before).value)
        self.extra_inputs[name] = InputDecl(name, unit, default, None, description, (self.name, "input"), late)
        self._changed()

    def add_parameter(self, param: Param):
        """Declare a graph-wide parameter used by several elements' expressions."""
        if not isinstance(param, Param):
            raise GraphError(f"expected a Param, got {param!r}")
        if param.name in self.extra_params:
            raise DuplicateNameError(param.name, "parameter declared twice")
        self.extra_params[param.name] = param
        self._changed()

    def add_output(self, name: str, expression, *, unit: str = "", description: str = ""):
        """Declare an output: any expression of states, inputs, parameters and
        bond variables (``e_<bond>``, ``f_<bond>``, or ``e_<element>`` /
        ``f_<element>`` for one-port elements, flow into the element)."""
        if not isinstance(name, str) or not name.isidentifier():
            raise GraphError(f"output name {name!r} is not a valid identifier")
        if name in self.outputs:
            raise DuplicateNameError(name, "output declared twice")
        self.outputs[name] = Output(name, expression, unit, description)
        self._changed()

    def add_guard(self, guard: Guard):
        """Declare a physical-domain condition over the graph's names (see
        :mod:`bondgraph.guards`); simulation and FMU steps that leave it fail, naming it."""
        if not isinstance(guard, Guard):
            raise GraphError(f"expected a Guard, got {guard!r}")
        if guard.name in self.extra_guards:
            raise DuplicateNameError(guard.name, "guard declared twice")
        self.extra_guards[guard.name] = guard
        self._changed()

    def guards(self) -> list[tuple[str, Guard]]:
        """Every guard as (owner, guard): the elements' own, then the graph's."""
        out = [(e.name, g) for e in self.elements.values() for g in e.guards()]
        out += [("graph", g) for g in self.extra_guards.values()]
        seen: dict[str, str] = {}
        for owner, g in out:
            if g.name in seen:
                raise DuplicateNameError(g.name, f"guard of {seen[g.name]} and of {owner}")
            seen[g.name] = owner
        return out

    def connect(self, tail, head, *, name: str | None = None) -> Bond:
        """Add a bond with power positive from `tail` to `head`.

        Parameters
        ----------
        tail, head : str, Element or (str, str)
            An element (name or object), or ``(element, port)`` for multiports.
            For a TF/GY the port is optional: a bond into it goes to port
            ``"1"``, a bond out of it leaves port ``"2"``.
        name : str, optional
            Bond name (default ``bond1``, ``bond2``...).

        Returns
        -------
        Bond
        """
        if name is None:
            k = len(self.bonds) + 1
            while f"bond{k}" in self.bonds or f"bond{k}" in self.elements:
                k += 1
            name = f"bond{k}"
        elif not isinstance(name, str) or not name.isidentifier():
            raise GraphError(f"bond name {name!r} is not a valid identifier")
        if name in self.bonds or name in self.elements:
            raise DuplicateNameError(name, "a bond or element already has that name")
        bond = Bond(name, self._port(tail, "tail"), self._port(head, "head"))
        if bond.tail.element == bond.head.element:
            raise PortError(f"bond {name!r} connects {bond.tail.element!r} to itself", element=bond.tail.element)
        self.bonds[name] = bond
        self._changed()
        return bond

    def _port(self, spec, end: str) -> Port:
        if isinstance(spec, tuple):
            if len(spec) != 2:
                raise PortError(f"port spec {spec!r} must be (element, port)")
            elem_name, port = spec
        else:
            elem_name, port = spec, None
        if isinstance(elem_name, Element):
            elem_name = elem_name.name
        element = self.elements.get(elem_name)
        if element is None:
            raise PortError(f"no element named {elem_name!r} in graph {self.name!r}; "
                            f"elements are {', '.join(self.elements) or '(none)'}", element=str(elem_name))
        if element.ports is None:  # junction: every bond is a port of its own
            if port not in (None, ""):
                raise PortError(f"junction {elem_name!r} has no named ports (got {port!r})",
                                element=elem_name, port=port)
            return Port(elem_name, "")
        used = {b.tail.port for b in self.bonds.values() if b.tail.element == elem_name}
        used |= {b.head.port for b in self.bonds.values() if b.head.element == elem_name}
        if port is None:
            want = "out" if end == "tail" else "in"
            free = [p for p in element.ports if p not in used]
            preferred = [p for p in free if element.direction(p) == want]
            if len(element.ports) == 1:
                port = element.ports[0]
            elif len(preferred) == 1 and element.kind in ("TF", "GY", "MTF", "MGY"):
                port = preferred[0]
            else:
                raise PortError(f"{element.kind} {elem_name!r} has ports {', '.join(element.ports)}: "
                                "say which one, e.g. connect(..., (name, port))", element=elem_name)
        if port not in element.ports:
            raise PortError(f"{element.kind} {elem_name!r} has no port {port!r}; its ports are "
                            f"{', '.join(repr(p) for p in element.ports)}", element=elem_name, port=port)
        if port in used:
            raise PortError(f"port {port or '(the only one)'} of {element.kind} {elem_name!r} already has a bond",
                            element=elem_name, port=port)
        return Port(elem_name, port)

    # -- queries -----------------------------------------------------------
    def bonds_of(self, element: str) -> list[tuple[Bond, str]]:
        """Bonds attached to `element` as (bond, end) with end "tail" or "head"."""
        out = []
        for b in self.bonds.values():
            if b.tail.element == element:
                out.append((b, "tail"))
            if b.head.element == element:
                out.append((b, "head"))
        return out

    def validate(self) -> None:
        """Check the structure; raise one GraphError listing every problem."""
        problems = []
        attached: dict[str, list[tuple[Bond, str]]] = {n: [] for n in self.elements}
        for b in self.bonds.values():
            attached[b.tail.element].append((b, "tail"))
            attached[b.head.element].append((b, "head"))
        for name, element in self.elements.items():
            bonds = attached[name]
            if element.ports is None:
                if len(bonds) < 2:
                    problems.append(f"junction {name!r} ({element.kind}) has {len(bonds)} bond(s); "
                                    "a junction needs at least two")
                continue
            used = {(b.tail.port if end == "tail" else b.head.port) for b, end in bonds}
            missing = [p for p in element.ports if p not in used]
            if missing:
                what = "its port" if element.ports == ("",) else "port(s) " + ", ".join(missing)
                problems.append(f"{element.kind} {name!r}: {what} has no bond")
        if not self.elements:
            problems.append(f"graph {self.name!r} has no elements")
        if problems:
            message = f"graph {self.name!r} is not complete:\n  - " + "\n  - ".join(problems)
            if all(p.startswith("junction") for p in problems):
                raise JunctionError(message, element=problems[0].split("'")[1], problems=problems)
            raise GraphError(message, problems)

    def names(self) -> dict[str, sp.Basic]:
        """The graph-wide symbol table (name -> symbol or expression).

        Holds ``t``, ``h_step`` (integration sub-step), every parameter, state, input and held variable, the
        bond variables ``e_<bond>``/``f_<bond>`` and, for one-port elements,
        ``e_<element>``/``f_<element>`` (flow in the element's natural
        direction).  Raises DuplicateNameError on a name used twice.
        """
        table: dict[str, sp.Basic] = {"t": TIME, "h_step": STEP}
        kinds: dict[str, str] = {"t": "time", "h_step": "the integration sub-step"}

        def put(name, what, value=None):
            if name in table:
                raise DuplicateNameError(name, f"used as {kinds[name]} and as {what}")
            table[name] = sym(name) if value is None else value
            kinds[name] = what

        params: dict[str, Param] = {}
        for p in list(self.extra_params.values()) + [p for e in self.elements.values() for p in e.parameters()]:
            old = params.get(p.name)
            if old is not None and (old.value, old.unit) != (p.value, p.unit):
                raise DuplicateNameError(p.name, f"two parameters of that name differ ({old.value} {old.unit} "
                                                 f"vs {p.value} {p.unit})")
            params[p.name] = p
        for pname in params:
            put(pname, "parameter")
        for e in self.elements.values():
            for sname, *_ in e.declared_states():
                put(sname, f"state of {e.name}")
            for hname, *_ in e.declared_held():
                put(hname, f"held variable of {e.name}")
        for decl in self.inputs():
            put(decl.name, "input")
        for b in self.bonds.values():
            put(f"e_{b.name}", f"effort of bond {b.name}")
            put(f"f_{b.name}", f"flow of bond {b.name}")
        for e in self.elements.values():
            if e.ports == ("",):
                bonds = self.bonds_of(e.name)
                if len(bonds) == 1 and f"e_{e.name}" not in table and f"f_{e.name}" not in table:
                    bond, end = bonds[0]
                    natural_end = "head" if e.direction("") == "in" else "tail"
                    f = table[f"f_{bond.name}"]
                    put(f"e_{e.name}", f"effort of {e.name}", table[f"e_{bond.name}"])
                    put(f"f_{e.name}", f"flow of {e.name}", f if end == natural_end else -f)
        return table

    def parameters(self) -> dict[str, Param]:
        """Every parameter by name."""
        params = dict(self.extra_params)
        for e in self.elements.values():
            for p in e.parameters():
                params.setdefault(p.name, p)
        return params

    def inputs(self) -> list[InputDecl]:
        """Every input (from sources and :meth:`add_input`), in declaration order."""
        seen: dict[str, InputDecl] = {}
        for e in self.elements.values():
            for decl in e.declared_inputs():
                if decl.name in seen:
                    raise DuplicateNameError(decl.name, f"input of {seen[decl.name].owner[0]} and of {e.name}")
                seen[decl.name] = decl
        for decl in self.extra_inputs.values():
            if decl.name in seen:
                raise DuplicateNameError(decl.name, f"input of {seen[decl.name].owner[0]} and declared again")
            seen[decl.name] = decl
        return list(seen.values())

    def prepare_expressions(self, names=None) -> None:
        """Parse every element's expressions against `names` (default: :meth:`names`),
        collecting every problem before raising one :class:`ExpressionError`."""
        names = self.names() if names is None else names
        problems = []
        for e in self.elements.values():
            try:
                e.prepare(names)
            except ExpressionError as exc:
                problems.append(exc)
        if len(problems) == 1:
            raise problems[0]
        if problems:
            raise ExpressionError("several expressions are wrong:\n  - " + "\n  - ".join(str(p) for p in problems),
                                  owner=", ".join(p.owner for p in problems),
                                  unknown=[u for p in problems for u in p.unknown])

    # -- derived results -----------------------------------------------------
    def causality(self):
        """Assign causality (SCAP) and return the :class:`~bondgraph.causality.CausalAssignment`."""
        from .causality import assign_causality
        self.validate()
        names = self.names()
        self.prepare_expressions(names)
        return assign_causality(self)

    def equations(self):
        """Derive the state equations (cached until the graph changes).

        Returns
        -------
        StateEquations

        Raises
        ------
        GraphError, CausalityError, ExpressionError, DerivationError
        """
        if self._cache is not None and self._cache[0] == self._version:
            return self._cache[1]
        from .equations import derive
        eqs = derive(self)
        self._cache = (self._version, eqs)
        return eqs

    def draw(self, path=None, **kwargs):
        """Render the graph with half-arrows and causal strokes (see :func:`bondgraph.draw.draw`)."""
        from .draw import draw
        return draw(self, path, **kwargs)

    def _repr_svg_(self) -> str:
        """The drawing as SVG text, for notebooks (Jupyter shows a BondGraph as its drawing)."""
        import io

        import matplotlib.pyplot as plt

        figure = self.draw()
        try:
            buffer = io.StringIO()
            figure.savefig(buffer, format="svg", bbox_inches="tight")
        finally:
            plt.close(figure)
        return buffer.getvalue()

    def to_dict(self) -> dict:
        """JSON-ready description (see docs/json-schema.md); :func:`bondgraph.io_json.save`
        writes it to a file and :func:`bondgraph.io_json.load` reads it back."""
        from .json_form import graph_to_dict
        return graph_to_dict(self)

    def __repr__(self) -> str:
        return f"BondGraph({self.name!r}, {len(self.elements)} elements, {len(self.bonds)} bonds)"

    def summary(self) -> str:
        """A few readable lines: elements and bonds."""
        lines = [f"{self.name}: {self.description}".rstrip(": ")]
        for e in self.elements.values():
            lines.append(f"  {e.kind:>5} {e.name}")
        for b in self.bonds.values():
            lines.append(f"  bond {b}")
        return "\n".join(lines)
