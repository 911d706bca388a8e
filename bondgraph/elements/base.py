"""What every element shares: ports, causal roles, and its contribution to the equations.

Causal roles
------------
At each of its ports an element either *sets the effort* of the bond (role
``EFFORT``, written ``"e"``; the other end then sets the flow) or *sets the
flow* (role ``FLOW``, ``"f"``).  An integral-causality I element sets the flow
(``f = p / m``), a C element the effort (``e = q / C``), an Se the effort.

Signs
-----
Each port has a natural power direction (``"in"`` for I, C, R, junctions and
port 1 of a two-port; ``"out"`` for sources and port 2).  A bond drawn the
other way flips the sign of the *flow* the element sees (effort is common to
both ends of a bond): ``flow_at_port = sign * f_bond`` with ``sign = +1`` when
the bond's half-arrow agrees with the natural direction.
"""
from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import ClassVar, Mapping

import sympy as sp

from ..errors import GraphError, ParameterError
from ..params import Param, as_param, domain
from ..symbols import as_expression

__all__ = [
    "EFFORT", "FLOW", "Element", "PortVars", "Contribution", "StateDecl",
    "DerivativeDecl", "HeldDecl", "InputDecl", "RoleConflict", "ELEMENT_KINDS",
]

EFFORT = "e"
FLOW = "f"

#: kind name -> element class; filled by ``Element.__init_subclass__``.
ELEMENT_KINDS: dict[str, type] = {}


class RoleConflict(Exception):
    """Raised by :meth:`Element.complete_roles` when known roles are inconsistent."""


@dataclass(frozen=True)
class PortVars:
    """The bond variables at one port of an element, as the element sees them."""

    bond: str
    e: sp.Symbol
    f: sp.Symbol
    sign: int
    role: str

    @property
    def flow(self) -> sp.Expr:
        """Flow in the port's natural direction (``sign * f``)."""
        return self.f if self.sign > 0 else -self.f


@dataclass(frozen=True)
class StateDecl:
    symbol: sp.Symbol
    rate: sp.Expr
    initial: float
    unit: str
    description: str
    owner: tuple


@dataclass(frozen=True)
class DerivativeDecl:
    """A storage element in derivative causality: ``output := factor * d(stored)/dt``.

    `stored` is the element's energy variable (p or q) written through the
    inverse constitutive law in terms of the bond variable it receives.
    """

    output: sp.Symbol
    factor: int
    stored: sp.Expr
    element: str
    bond: str
    state_name: str


@dataclass(frozen=True)
class HeldDecl:
    symbol: sp.Symbol
    update: sp.Expr
    initial: float
    unit: str
    description: str
    owner: tuple


@dataclass(frozen=True)
class InputDelay:
    """An input that is another input, late: :math:`u_d(t) = u(t - T)`.

    `source` is the input delayed, `time` the name of the graph parameter :math:`T` (s), and
    `before` the value :math:`u_d` takes while :math:`t - T` lies before the start of the run
    (where the source rested): a number, the name of a graph parameter holding it (a value a fit
    can find, as it finds :math:`T`), or None: the source's value at the start.  Simulators realise it
    exactly on the source's samples; an FMU, which has no delay primitive, as Pade states
    (:meth:`bondgraph.editing.GraphEditing.with_delays_realised`).
    """

    source: str
    time: str
    before: float | str | None = None


@dataclass(frozen=True)
class InputDecl:
    name: str
    unit: str
    default: float
    function: object | None  # str or sympy expression in t, or None
    description: str
    owner: tuple
    delay: InputDelay | None = None


@dataclass
class Contribution:
    """What an element adds to the equations, given its causality."""

    defs: list = field(default_factory=list)        # (bond symbol, expression)
    locals: list = field(default_factory=list)      # (local symbol ``<element>.<name>``, expression)
    states: list = field(default_factory=list)      # StateDecl
    derivative: list = field(default_factory=list)  # DerivativeDecl
    held: list = field(default_factory=list)        # HeldDecl


class Element(ABC):
    """Base class of bond-graph elements.

    Subclasses set ``kind`` (the JSON name), ``ports`` (fixed port names, or
    ``None`` for junctions, whose ports are their bonds) and implement
    :meth:`complete_roles` and :meth:`contribute`.
    """

    kind: ClassVar[str] = ""
    #: Fixed port names; ``None`` for junctions (any number of bonds).
    ports: ClassVar[tuple | None] = ("",)
    #: Natural power direction per port ("in" or "out").
    directions: ClassVar[Mapping[str, str]] = {"": "in"}

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        if cls.kind:
            ELEMENT_KINDS[cls.kind] = cls

    def __init__(self, name: str, *, description: str = ""):
        if not isinstance(name, str) or not name.isidentifier():
            raise GraphError(f"element name {name!r} is not a valid identifier "
                             "(letters, digits and _, not starting with a digit)")
        self.name = name
        self.description = description
        self.locals: dict[str, object] = {}
        self._local_defs: list = []

    # -- named locals --------------------------------------------------------
    def _set_locals(self, locals_) -> None:
        """Store the element's named locals (name -> expression, in evaluation order)."""
        items = dict(locals_ or {})
        bad = [k for k in items if not isinstance(k, str) or not k.isidentifier()]
        if bad:
            raise GraphError(f"{self.kind} {self.name!r}: local names must be identifiers, got "
                             f"{', '.join(map(repr, bad))}")
        self.locals = items

    def local_symbol(self, local: str) -> sp.Symbol:
        """The symbol of the element's local `local`: ``<element>.<local>`` (real)."""
        return sp.Symbol(f"{self.name}.{local}", real=True)

    def _parse_locals(self, table: Mapping[str, sp.Basic]) -> dict:
        """Parse the locals in order (each may use the earlier ones) into
        ``self._local_defs``; returns `table` extended with the local names."""
        table = dict(table)
        self._local_defs = []
        for key, text in self.locals.items():
            if key in table:
                raise GraphError(f"{self.kind} {self.name!r}: local {key!r} shadows a name of the graph "
                                 "(a parameter, state, input or port variable); rename it")
            symbol = self.local_symbol(key)
            self._local_defs.append((symbol, self._expr(text, table, f"local {key}")))
            table[key] = symbol
        return table

    # -- declarations (used to build the graph's name table) ----------------
    def parameters(self) -> list[Param]:
        return []

    def declared_states(self) -> list[tuple[str, str, float, str]]:
        """(name, unit, initial, description) of the states this element may own."""
        return []

    def declared_inputs(self) -> list[InputDecl]:
        return []

    def declared_held(self) -> list[tuple[str, str, float, str]]:
        """(name, unit, initial, description) of held (discrete) variables."""
        return []

    @property
    def fixed_step(self) -> float | None:
        """Largest integration step this element honours, s (``None``: any)."""
        return None

    def direction(self, port: str) -> str:
        return self.directions.get(port, "in")

    def prepare(self, names: Mapping[str, sp.Basic]) -> None:
        """Parse the element's expressions against the graph's names.

        Called once per derivation before causality is assigned; raises
        :class:`~bondgraph.errors.ExpressionError` naming the element.
        """

    def guards(self) -> list:
        """Physical-domain conditions of the element (:class:`~bondgraph.guards.Guard`), in
        the graph's names; a simulation or FMU step that leaves them fails, naming them."""
        return []

    # -- causality ---------------------------------------------------------
    def fixed_roles(self) -> dict[str, str] | None:
        """Roles the element imposes whatever the rest of the graph does."""
        return None

    def preferred_roles(self) -> dict[str, str] | None:
        """Roles of integral causality, for storage elements."""
        return None

    def complete_roles(self, roles: dict) -> dict:
        """Infer unknown roles (value ``None``) from known ones; raise RoleConflict."""
        fixed = self.fixed_roles()
        if fixed is None:
            return dict(roles)
        for port, role in roles.items():
            if role is not None and role != fixed[port]:
                where = f"at port {port}" if port else "on its bond"
                raise RoleConflict(f"must set the {_word(fixed[port])} {where}, "
                                   "but the element at the other end of the bond sets it too")
        return dict(fixed)

    # -- equations ---------------------------------------------------------
    @abstractmethod
    def contribute(self, ports: Mapping[str, PortVars], names: Mapping[str, sp.Basic]) -> Contribution:
        """The element's equations given its ports' causal roles (see :class:`Contribution`)."""

    # -- serialisation -----------------------------------------------------
    def to_dict(self) -> dict:
        """JSON-ready description; ``from_dict(to_dict())`` rebuilds the element."""
        data = {"kind": self.kind, "name": self.name}
        data.update(self._spec())
        if self.description:
            data["description"] = self.description
        return data

    def _spec(self) -> dict:
        return {}

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.name!r})"

    # -- helpers for subclasses -------------------------------------------
    def _expr(self, value, names, what: str) -> sp.Expr:
        return as_expression(value, names, owner=f"{self.kind} {self.name!r} {what}")


def _word(role: str) -> str:
    return "effort" if role == EFFORT else "flow"


def other(role: str) -> str:
    """The role at the other end of a bond."""
    return FLOW if role == EFFORT else EFFORT


def param_dict(params, owner: str) -> dict[str, Param]:
    """Normalise ``params`` (mapping name -> number or Param, or list of Param)."""
    if params is None:
        return {}
    out = {}
    items = params.values() if isinstance(params, Mapping) and all(
        isinstance(v, Param) for v in params.values()) else None
    if items is not None:
        for p in items:
            out[p.name] = p
        return out
    if isinstance(params, Mapping):
        for key, value in params.items():
            if isinstance(value, Mapping):
                out[key] = Param(key, value.get("value"), value.get("unit", ""), value.get("description", ""),
                                 min=value.get("min"), max=value.get("max"))
            else:
                out[key] = as_param(value, key, "")
        return out
    for p in params:
        if not isinstance(p, Param):
            raise ParameterError(f"{owner}: parameters must be Param objects or a mapping, got {p!r}")
        out[p.name] = p
    return out


def element_param(value, name: str, unit: str | None, default_unit: str, description: str,
                  *, min: float | None = None) -> Param:
    """The parameter an element owns under its own name.

    `value` is a number or a :class:`Param`, whose unit, description and
    range are kept (an explicit `unit` wins, then the Param's, then
    `default_unit`); `min` is the element's physical lower bound (0 for a
    mass, a compliance, a resistance), used where the Param gives none.
    """
    if isinstance(value, Param):
        return Param(name, value.value, unit if unit is not None else (value.unit or default_unit),
                     value.description or description,
                     min=value.min if value.min is not None else min, max=value.max)
    return Param(name, value, unit if unit is not None else default_unit, description, min=min)


def unit_of(domain_name: str, quantity: str) -> str:
    return getattr(domain(domain_name), quantity)
