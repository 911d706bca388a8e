"""Sequential causality assignment procedure (SCAP), integral causality preferred.

Order (Karnopp, Margolis & Rosenberg, *System Dynamics*, ch. 5):

1. elements with fixed causality (sources, non-invertible R laws, fields,
   equation-defined elements), each followed by propagation through
   junctions and two-ports;
2. storage elements one at a time in integral causality, with propagation;
   one already forced the other way is in *derivative causality*;
3. remaining R elements, arbitrarily (effort out), with propagation: each
   such choice signals an *algebraic loop*;
4. any bond still free (e.g. between two two-ports), arbitrarily.

Conflicts do not stop the procedure: every one found is collected and
reported together in a :class:`~bondgraph.errors.CausalityError`, naming the
element and the bonds involved.
"""
from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field

from .elements.base import EFFORT, FLOW, RoleConflict
from .errors import CausalityError

__all__ = ["assign_causality", "CausalAssignment", "Conflict"]


@dataclass(frozen=True)
class Conflict:
    """One causal conflict: the elements involved, their bonds, and why.

    ``element`` is the element where the conflict showed; ``elements`` adds
    the one at the other end of the bond when two ends disagree.
    """

    element: str
    bonds: tuple
    reason: str
    elements: tuple = ()

    def __post_init__(self):
        if not self.elements:
            object.__setattr__(self, "elements", (self.element,))

    def __str__(self) -> str:
        return f"{' / '.join(self.elements)} (bond{'s' if len(self.bonds) != 1 else ''} {', '.join(self.bonds)}): {self.reason}"


@dataclass
class CausalAssignment:
    """Which end of every bond sets its effort.

    Attributes
    ----------
    effort_by : dict bond name -> "tail" or "head"
        The end whose element sets the effort; the other end sets the flow.
        (The causal stroke is drawn at the other end, next to the element
        that receives the effort.)
    derivative : list of (element, bond)
        Storage in derivative causality.
    arbitrary : list of str
        R elements and bonds whose causality was chosen arbitrarily.
    """

    effort_by: dict = field(default_factory=dict)
    derivative: list = field(default_factory=list)
    arbitrary: list = field(default_factory=list)

    def role(self, bond, end: str) -> str:
        """Role of the element at `end` of `bond`: EFFORT or FLOW."""
        return EFFORT if self.effort_by[bond.name] == end else FLOW

    def stroke_end(self, bond) -> str:
        """The end of `bond` where the causal stroke is drawn."""
        return "head" if self.effort_by[bond.name] == "tail" else "tail"


class _Scap:
    def __init__(self, graph):
        self.graph = graph
        self.result = CausalAssignment()
        self.conflicts: list[Conflict] = []
        self.conflicted: set[str] = set()
        # element name -> list of (port key, bond, end)
        self.ports = {name: [] for name in graph.elements}
        for b in graph.bonds.values():
            self.ports[b.tail.element].append((b.tail.port or b.name if _is_junction(graph, b.tail.element)
                                               else b.tail.port, b, "tail"))
            self.ports[b.head.element].append((b.head.port or b.name if _is_junction(graph, b.head.element)
                                               else b.head.port, b, "head"))

    def roles_of(self, name: str) -> dict:
        out = {}
        for key, bond, end in self.ports[name]:
            by = self.result.effort_by.get(bond.name)
            out[key] = None if by is None else (EFFORT if by == end else FLOW)
        return out

    def conflict(self, element: str, bonds, reason: str, other: str | None = None):
        if element in self.conflicted:
            return
        self.conflicted.add(element)
        elements = (element,) if other is None else (element, other)
        self.conflicts.append(Conflict(element, tuple(bonds), reason, elements))

    def set_role(self, name: str, key: str, role: str, queue: deque) -> None:
        for k, bond, end in self.ports[name]:
            if k != key:
                continue
            setter = end if role == EFFORT else _opposite(end)
            current = self.result.effort_by.get(bond.name)
            if current is None:
                self.result.effort_by[bond.name] = setter
                queue.append(bond.tail.element)
                queue.append(bond.head.element)
            elif current != setter:
                other = bond.head.element if end == "tail" else bond.tail.element
                word = "effort" if role == EFFORT else "flow"
                self.conflict(name, [bond.name],
                              f"{_kind(self.graph, name)} {name} must set the {word} on bond {bond.name}, "
                              f"but {_kind(self.graph, other)} {other} at its other end already does", other)
            return

    def impose(self, name: str, roles: dict) -> None:
        queue: deque = deque()
        for key, role in roles.items():
            self.set_role(name, key, role, queue)
        self.propagate(queue)

    def propagate(self, queue: deque) -> None:
        while queue:
            name = queue.popleft()
            if name in self.conflicted:
                continue
            element = self.graph.elements[name]
            roles = self.roles_of(name)
            try:
                completed = element.complete_roles(roles)
            except RoleConflict as exc:
                self._role_conflict(name, exc)
                continue
            for key, role in completed.items():
                if roles.get(key) is None and role is not None:
                    self.set_role(name, key, role, queue)

    def _role_conflict(self, name: str, exc: RoleConflict) -> None:
        ports = self.ports[name]
        other = None
        if len(ports) == 1:  # a one-port: the element across its bond is the other party
            _, bond, end = ports[0]
            other = bond.head.element if end == "tail" else bond.tail.element
        element = self.graph.elements[name]
        self.conflict(name, [b.name for _, b, _ in ports], f"{element.kind} {name}: {exc}", other)

    def run(self) -> CausalAssignment:
        g = self.graph
        elements = list(g.elements.values())
        for e in elements:   # 1. fixed causality
            if e.preferred_roles() is None and e.fixed_roles() is not None:
                self.impose(e.name, e.fixed_roles())
        storage = [e for e in elements if e.preferred_roles() is not None]
        for e in storage:    # 2. storage, integral preferred
            roles = self.roles_of(e.name)
            if all(r is None for r in roles.values()):
                self.impose(e.name, e.preferred_roles())
        for e in storage:
            roles = self.roles_of(e.name)
            preferred = e.preferred_roles()
            if any(roles[k] is not None and roles[k] != preferred[k] for k in preferred):
                bond = self.ports[e.name][0][1].name
                self.result.derivative.append((e.name, bond))
        for e in elements:   # 3. flexible R: arbitrary choice, signals an algebraic loop
            if e.kind == "R" and self.roles_of(e.name)[""] is None:
                self.result.arbitrary.append(e.name)
                self.impose(e.name, {"": EFFORT})
        for b in g.bonds.values():   # 4. free bonds
            if b.name not in self.result.effort_by:
                self.result.arbitrary.append(b.name)
                queue: deque = deque()
                self.result.effort_by[b.name] = "tail"
                queue.extend([b.tail.element, b.head.element])
                self.propagate(queue)
        for e in elements:   # final check: every element's roles are consistent
            if e.name in self.conflicted:
                continue
            try:
                e.complete_roles(self.roles_of(e.name))
            except RoleConflict as exc:
                self._role_conflict(e.name, exc)
        if self.conflicts:
            raise CausalityError(self.conflicts)
        return self.result


def _opposite(end: str) -> str:
    return "head" if end == "tail" else "tail"


def _is_junction(graph, name: str) -> bool:
    return graph.elements[name].ports is None


def _kind(graph, name: str) -> str:
    return graph.elements[name].kind


def assign_causality(graph) -> CausalAssignment:
    """Run SCAP on a validated graph whose elements have been prepared.

    Returns
    -------
    CausalAssignment

    Raises
    ------
    CausalityError
        Listing every conflict with its element and bonds.
    """
    return _Scap(graph).run()
