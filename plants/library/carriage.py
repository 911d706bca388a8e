"""A force-driven rigid carriage (a ball-screw axis as a nominal user would first write it).

Bond graph::

    Se F -> 1 v_cart -> I m
                     -> C position (law 0: a position meter, no force)

No friction, no spring: the model integrates its input twice, so any
unmodelled force (guide friction, a cable, gravity on a tilted axis) makes
its simulation drift away from a recording.  The position is the
displacement of a zero-stiffness C (as the exoskeleton's trunk angle): it
integrates the junction velocity and takes no force.
"""
from __future__ import annotations

from bondgraph.elements import C, I, One, Se
from bondgraph.graph import BondGraph
from bondgraph.params import Param

__all__ = ["carriage"]


def carriage(*, m: float = 20.0) -> BondGraph:
    """Force ``F`` (N, input) on a carriage of mass ``m`` (kg, carriage + reflected screw inertia).

    States ``p_m`` (momentum, N s) and ``x_pos`` (position, m); outputs
    ``x`` (m) and ``v`` (m/s).
    """
    g = BondGraph("carriage", description="force-driven rigid carriage: no friction, no spring")
    g.add(Se("F", 0.0, domain="translation", description="drive force (input)"))
    g.add(One("v_cart", description="carriage velocity"))
    g.add(I("m", Param("m", m, "kg", "carriage mass with the reflected screw and rotor inertia"),
            domain="translation"))
    g.add(C("position", law="0", state="x_pos", domain="translation",
            description="zero-stiffness position meter: q = integral of v, no force"))
    g.connect("F", "v_cart")
    g.connect("v_cart", "m")
    g.connect("v_cart", "position")
    g.add_output("x", "x_pos", unit="m", description="carriage position")
    g.add_output("v", "f_m", unit="m/s", description="carriage velocity")
    return g
