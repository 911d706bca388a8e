"""0- and 1-junctions.

Every bond of a junction is one of its ports (named by the bond), with
``sign = +1`` when the bond points into the junction.

* 0-junction: common effort, ``sum(sign * f) = 0``; exactly one bond (the
  *strong bond*) brings the effort in, and the junction sets the flow there.
* 1-junction: common flow, ``sum(sign * e) = 0``; exactly one bond brings the
  flow in, and the junction sets the effort there.
"""
from __future__ import annotations

import sympy as sp

from .base import EFFORT, FLOW, Contribution, Element, RoleConflict

__all__ = ["Zero", "One"]


class _Junction(Element):
    ports = None
    directions = {}
    _strong = FLOW      # role the junction has at its strong bond
    _common = "effort"

    def complete_roles(self, roles):
        weak = EFFORT if self._strong == FLOW else FLOW
        strong = [p for p, r in roles.items() if r == self._strong]
        unknown = [p for p, r in roles.items() if r is None]
        if len(strong) > 1:
            raise RoleConflict(
                f"{len(strong)} bonds ({', '.join(strong)}) each impose the junction's common "
                f"{self._common}; exactly one may")
        if strong:
            return {p: (self._strong if p == strong[0] else weak) for p in roles}
        if not unknown:
            raise RoleConflict(f"no bond imposes the junction's common {self._common}; exactly one must")
        if len(unknown) == 1:
            return {p: (self._strong if r is None else r) for p, r in roles.items()}
        return dict(roles)

    def contribute(self, ports, names):
        strong = next(p for p in ports.values() if p.role == self._strong)
        others = [p for p in ports.values() if p is not strong]
        common = strong.e if self._strong == FLOW else strong.f
        defs = [((p.e if self._strong == FLOW else p.f), common) for p in others]
        total = sp.Add(*[(p.sign * (p.f if self._strong == FLOW else p.e)) for p in others])
        value = -strong.sign * total
        defs.append(((strong.f if self._strong == FLOW else strong.e), value))
        return Contribution(defs=defs)


class Zero(_Junction):
    """0-junction: common effort, flows sum to zero."""

    kind = "0"
    _strong = FLOW
    _common = "effort"


class One(_Junction):
    """1-junction: common flow, efforts sum to zero."""

    kind = "1"
    _strong = EFFORT
    _common = "flow"
