"""Constitutive laws as places: a correction to what one element's law sets on one bond.

A muscle's force law sets the force on the bond from the muscle to its lever arm; no junction
sits on that bond, so no junction place can say "this law is wrong".  A *law place*
(``Place("law", element, bond)``) is one port of an element with a constitutive law (storage,
field, resistor, equation element: not a source, whose law is the input's, nor a transformer or
gyrator, whose modulus is geometry), where the port's bond does not end at a junction.  A
correction there is

* an extra **effort** in series with the law when the element sets the bond's effort (a
  1-junction put into the bond: the muscle's force law), or
* an extra **flow** beside the law when it sets the flow (a 0-junction put into the bond).

Splitting the bond with that junction (:func:`split_law`, through
:meth:`BondGraph.insert_on_bond <bondgraph.editing.GraphEditing.insert_on_bond>`) leaves the
equations unchanged (a two-bond junction passes both variables through), and on the split graph
the law place is a junction like any other: the graph location estimates its correction, and the
junction kinds (friction, Dahl hysteresis, a constant load, a leak) propose and build there.  A
port whose bond already ends at a junction is that junction's place (a valve's flow law into a
chamber's 0-junction is the chamber's flow place; a spring's law on its 1-junction is the storage
place of ``nonlinear_stiffness``), so it is not listed twice.
"""
from __future__ import annotations

from dataclasses import dataclass

from bondgraph.elements import SOURCE_KINDS, TWO_PORT_KINDS

from .errors import DiagnosisError, UnknownNameError
from .place import Place

__all__ = ["LawPort", "law_ports", "law_places", "split_law", "split_laws", "at_junction", "acts_on"]

#: two-ports a law's effort or flow passes through unchanged but for a modulus
_TWO_PORTS = TWO_PORT_KINDS

#: element kinds whose law is not a place of its own: junctions, sources (the law is the
#: input's: an input place), transformers and gyrators (a modulus is geometry, not physics)
_NOT_LAWS = frozenset({"0", "1"}) | SOURCE_KINDS | TWO_PORT_KINDS


@dataclass(frozen=True)
class LawPort:
    """One port of an element whose law sets a variable of a bond that ends at no junction.

    Attributes
    ----------
    element : str
        The element owning the law.
    port : str
        Its port ("" for a one-port).
    bond : str
        The port's bond.
    sets : {"effort", "flow"}
        What the law sets on the bond (its causal role there).
    junction : str
        The name the splitting junction takes (``<element>_<port>_law``, or ``<element>_law``).
    """

    element: str
    port: str
    bond: str
    sets: str
    junction: str

    @property
    def place(self) -> Place:
        return Place("law", self.element, self.bond)

    @property
    def junction_kind(self) -> str:
        """``"1"`` (an effort in series) when the law sets the effort, else ``"0"``."""
        return "1" if self.sets == "effort" else "0"


def law_ports(graph) -> list[LawPort]:
    """Every law port of `graph` (see the module docstring), in the graph's element order.

    Examples
    --------
    >>> from plants import library
    >>> [(p.element, p.port, p.sets) for p in law_ports(library.build("pam"))]
    [('muscle1', 'mech', 'effort'), ('muscle2', 'mech', 'effort')]
    >>> law_ports(library.build("mass-spring-damper"))
    []
    """
    from bondgraph import BondGraph

    if not isinstance(graph, BondGraph):
        return []
    causal = None
    taken = set(graph.names()) | set(graph.elements) | set(graph.bonds)
    out = []
    for name, element in graph.elements.items():
        if element.kind in _NOT_LAWS:
            continue
        ports = [(b, end) for b, end in graph.bonds_of(name)]
        for bond, end in ports:
            other = bond.head.element if end == "tail" else bond.tail.element
            if graph.elements[other].kind in ("0", "1"):
                continue
            if causal is None:
                causal = graph.causality()
            port = (bond.tail.port if end == "tail" else bond.head.port) or ""
            sets = "effort" if causal.effort_by.get(bond.name) == end else "flow"
            base = f"{name}_{port}_law" if port and len(ports) > 1 else f"{name}_law"
            junction, k = base, 1
            while junction in taken:
                k += 1
                junction = f"{base}_{k}"
            taken.add(junction)
            out.append(LawPort(name, port, bond.name, sets, junction))
    return out


def law_places(graph) -> list[Place]:
    """The law places of `graph` (:func:`law_ports` as :class:`~diagnosis.place.Place` s)."""
    return [p.place for p in law_ports(graph)]


def law_port(graph, place: Place) -> LawPort:
    """The :class:`LawPort` of a law `place`; an :class:`UnknownNameError` names the known ones."""
    if place.kind != "law":
        raise DiagnosisError(f"{place} is not a law place")
    ports = law_ports(graph)
    for p in ports:
        if p.element == place.name and (place.bond is None or p.bond == place.bond):
            return p
    raise UnknownNameError("law place", place.name, [f"{p.element} (bond {p.bond})" for p in ports],
                           model=graph.name)


def split_law(graph, place: Place):
    """`graph` with the law `place`'s bond split by its junction: ``(new graph, junction name)``.

    The junction (a 1-junction for an effort law, a 0-junction for a flow law) passes both
    variables through, so the equations are those of `graph`; a correction hung on it acts on
    the law alone.
    """
    from bondgraph import One, Zero

    port = law_port(graph, place)
    cls = One if port.junction_kind == "1" else Zero
    junction = cls(port.junction, description=f"the {port.sets} law of {port.element}"
                   + (f" at its port {port.port}" if port.port else ""))
    return graph.insert_on_bond(port.bond, junction), port.junction


def at_junction(graph, place: Place):
    """``(graph, place)`` where a correction at `place` is a junction's: for a law place the split
    graph and its splitting junction (:func:`split_law`), any other place unchanged."""
    if place.kind != "law":
        return graph, place
    split, junction = split_law(graph, place)
    return split, Place("junction", junction)


def split_laws(graph, places):
    """`graph` with every law place among `places` split: ``(graph, {place: junction name})``."""
    out = {}
    for place in places:
        if place.kind == "law":
            graph, out[place] = split_law(graph, place)
    return graph, out


def acts_on(graph, place: Place) -> str | None:
    """The junction a law place reaches through two-ports only (its lever arm, a gear): there a
    correction of the law is a correction of the junction scaled by the moduli.  None when the
    bond leads to another law first.

    Examples
    --------
    >>> from plants import library
    >>> pam = library.build("pam")
    >>> acts_on(pam, law_places(pam)[0])
    'seesaw'
    """
    port = law_port(graph, place)
    came, at = port.element, None
    bond = graph.bonds[port.bond]
    at = bond.head.element if bond.tail.element == came else bond.tail.element
    seen = {came}
    while graph.elements[at].kind in _TWO_PORTS and at not in seen:
        seen.add(at)
        onward = [b for b, _ in graph.bonds_of(at) if b.name != bond.name]
        if len(onward) != 1:
            return None
        bond = onward[0]
        came, at = at, bond.head.element if bond.tail.element == at else bond.tail.element
    return at if graph.elements[at].kind in ("0", "1") else None
