"""What the kinds acting on a storage element share: the C's displacement scale, unit and
stiffness; the C and the electrical I elements at a junction."""
from __future__ import annotations

import numpy as np
import sympy as sp

from bondgraph.params import DOMAINS

from ..catalogue_common import junction_elements

__all__ = ["capacitors", "carries_effort", "inductors", "displacement_scale", "stiffness_scale", "units_of"]


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


def displacement_scale(site, element) -> float:
    """RMS of the C's displacement in the nominal simulation (the junction's scale without one)."""
    q = site.values.get(f"state:{element.state}")
    scale = float(np.sqrt(np.mean(q ** 2))) if q is not None else 0.0
    return scale if scale > 0 and np.isfinite(scale) else site.scales.displacement


def stiffness_scale(site, element) -> float:
    """The junction's effort scale over the C's displacement scale."""
    return site.scales.effort / displacement_scale(site, element)


def units_of(element) -> tuple[str, str]:
    """(stiffness unit, displacement unit) of a C's domain ("" outside the known domains)."""
    if element.domain in DOMAINS:
        return DOMAINS[element.domain].stiffness, DOMAINS[element.domain].displacement
    return "", ""
