"""A chain of N mass-spring-damper stages, the derivation benchmark's graph."""
from __future__ import annotations

from bondgraph.elements import C, I, One, R, Se, Zero
from bondgraph.graph import BondGraph
from ..errors import ArgumentError

__all__ = ["mass_spring_chain"]


def mass_spring_chain(n: int = 5, *, m: float = 1.0, b: float = 0.5, compliance: float = 0.01) -> BondGraph:
    """Se -> [1: I, R] -> [0: C] -> [1: I, R] -> ... with `n` stages (2 n states).

    Stage k is a 1-junction with inertia ``m<k>`` and damper ``b<k>``
    followed by a 0-junction with compliance ``k<k>``.
    """
    if not isinstance(n, int) or n < 1:
        raise ArgumentError(f"chain length must be a positive integer, got {n!r}")
    g = BondGraph(f"chain{n}", description=f"chain of {n} mass-spring-damper stages")
    g.add(Se("F", 1.0, domain="translation"))
    prev = "F"
    for k in range(1, n + 1):
        g.add(One(f"j1_{k}"))
        g.connect(prev, f"j1_{k}")
        for e in (I(f"m{k}", m, domain="translation"), R(f"b{k}", b, domain="translation")):
            g.add(e)
            g.connect(f"j1_{k}", e.name)
        g.add(Zero(f"j0_{k}"))
        g.connect(f"j1_{k}", f"j0_{k}")
        g.add(C(f"k{k}", compliance, domain="translation"))
        g.connect(f"j0_{k}", f"k{k}")
        prev = f"j0_{k}"
    return g
