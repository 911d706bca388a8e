"""What the kinds acting on a storage element share: the C's displacement scale, unit and
stiffness; the C and the electrical I elements at a junction."""
from __future__ import annotations

import numpy as np
import sympy as sp

from bondgraph.params import DOMAINS

from ..catalogue_common import ambient_effort, fresh_name, junction_elements

__all__ = ["capacitors", "carries_effort", "inductors", "displacement_scale", "stiffness_scale", "units_of",
           "held_start", "held_start_law", "START_PREFIXES"]

#: the names of :func:`held_start`'s constants: the storage's content and what its law gives there
START_PREFIXES = ("q0_", "e0_")


def capacitors(site) -> list:
    """The C elements bonded to the site's junction, in bond order."""
    return [element for element, _ in junction_elements(site.graph, site.name) if element.kind == "C"]


def carries_effort(element) -> bool:
    """Whether a C's law is not identically zero (a carriage's position meter, ``law="0"``,
    carries nothing: a play or a dead band in front of it changes no effort)."""
    law = getattr(element, "law", None)
    if getattr(element, "value", None) is not None or law is None:
        return True
    try:
        return sp.sympify(str(law)) != 0
    except (sp.SympifyError, TypeError):
        return True


def inductors(site) -> list:
    """The electrical I elements bonded to the site's junction, in bond order."""
    return [element for element, _ in junction_elements(site.graph, site.name)
            if element.kind == "I" and element.domain == "electrical"]


def displacement_scale(site, element, relaxed: float = 0.0) -> float:
    """RMS of the C's displacement from its `relaxed` content in the nominal simulation (the
    junction's scale without one)."""
    q = site.values.get(f"state:{element.state}")
    scale = float(np.sqrt(np.mean((q - relaxed) ** 2))) if q is not None else 0.0
    return scale if scale > 0 and np.isfinite(scale) else site.scales.displacement


def stiffness_scale(site, element) -> float:
    """The junction's effort scale over the C's displacement scale."""
    return site.scales.effort / displacement_scale(site, element)


def units_of(element) -> tuple[str, str]:
    """(stiffness unit, displacement unit) of a C's domain ("" outside the known domains)."""
    if element.domain in DOMAINS:
        return DOMAINS[element.domain].stiffness, DOMAINS[element.domain].displacement
    return "", ""


def held_start(site, element) -> tuple:
    """The constants that hold a linear storage's start when its value is refitted: its content
    ``q0_<name>`` at the recording's first sample (the nominal run's) and what its nominal law
    gives there, ``e0_<name>`` (a C's effort, an I's flow); () where the content starts at 0.

    The state a recording starts in is stated (or estimated) as a content, a heat or a momentum,
    but what is known is the temperature or the velocity: a heater block's capacity refitted
    12 % lower, its content held, had started the block 36 K above the room it stood in.  With
    these, the refitted law is :func:`held_start_law`'s, which gives ``e0`` at ``q0`` for any value.
    An I's flow is held (a mass's velocity, never its momentum, is what is known), a C's effort
    only where its content's zero is no relaxed state, at a 0-junction whose ambient effort is not
    0 (a heat capacity in absolute temperature: :func:`~diagnosis.catalogue_common.ambient_effort`):
    a spring's start is its deflection, and its refitted stiffness changes the force there.
    """
    if element.value is None or not element.state:
        return ()
    if element.kind == "C" and not (site.door == "0" and ambient_effort(site.graph, site.name, site.effort) != 0.0):
        return ()
    q = site.values.get(f"state:{element.state}")
    q0 = float(q[0]) if q is not None and len(q) else 0.0
    if q0 == 0.0 or not np.isfinite(q0):
        return ()
    v = float(element.value.value)
    e0 = v * q0 if getattr(element, "stiffness_form", False) else q0 / v
    domain = DOMAINS.get(element.domain)
    if element.kind == "C":
        units = (domain.displacement, domain.effort) if domain else ("", "")
        words = ("content", "effort")
    else:
        units = (domain.momentum, domain.flow) if domain else ("", "")
        words = ("momentum", "flow")
    name = element.name
    return ((fresh_name(site.taken, f"{START_PREFIXES[0]}{name}"), q0, units[0],
             f"{words[0]} of {name} at the recording's start"),
            (fresh_name(site.taken, f"{START_PREFIXES[1]}{name}"), e0, units[1],
             f"{words[1]} of {name} there, held when its value is refitted"))


def held_start_law(old, x, constants):
    """A storage's law `old` (a sympy expression in its local variable `x`) shifted to give the
    constant ``e0`` at the content ``q0`` whatever its refitted value (:func:`held_start`'s
    `constants`; `old` itself without them): ``old - old(q0) + e0``, a C's ``(q - q0)/C + e0``."""
    named = {c[0][:3]: sp.Symbol(c[0]) for c in constants if c[0][:3] in START_PREFIXES}
    if len(named) < 2:
        return old
    q0, e0 = named[START_PREFIXES[0]], named[START_PREFIXES[1]]
    return old - old.subs(x, q0) + e0
