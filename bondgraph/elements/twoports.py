"""Two-ports: transformers TF, MTF and gyrators GY, MGY.

Port ``"1"`` is the power input and port ``"2"`` the output (natural
directions); with flows taken in those directions

* TF:  ``e1 = m * e2``, ``f2 = m * f1``
* GY:  ``e1 = r * f2``, ``e2 = r * f1``

so that ``e1 f1 = e2 f2`` (power conserving).  MTF/MGY take the modulus as an
expression of states, inputs, parameters, held or bond variables.
"""
from __future__ import annotations

from .base import EFFORT, Contribution, Element, RoleConflict, element_param, other, param_dict

__all__ = ["TF", "GY", "MTF", "MGY"]


class _TwoPort(Element):
    ports = ("1", "2")
    directions = {"1": "in", "2": "out"}
    _symbol = "m"

    def __init__(self, name: str, modulus, *, params=None, unit: str = "", description: str = ""):
        super().__init__(name, description=description)
        self.params = param_dict(params, f"{self.kind} {name!r}")
        self.modulus = modulus
        self.unit = unit
        self._modulus_param = None
        if self.kind in ("TF", "GY"):
            self._modulus_param = element_param(modulus, name, unit or None, "",
                                                f"modulus of {self.kind} {name}")
            self.params[name] = self._modulus_param
        self._m = None

    def parameters(self):
        return list(self.params.values())

    def prepare(self, names):
        if self._modulus_param is not None:
            self._m = names[self.name]
        else:
            self._m = self._expr(self.modulus, names, "modulus")

    def _spec(self):
        spec = {}
        if self._modulus_param is not None:
            spec["modulus"] = self._modulus_param.value
        else:
            spec["modulus"] = str(self.modulus)
        unit = self._modulus_param.unit if self._modulus_param is not None else self.unit
        if unit:
            spec["unit"] = unit
        extra = {k: p.to_dict() for k, p in self.params.items() if p is not self._modulus_param}
        if extra:
            spec["params"] = extra
        return spec


class _Transformer(_TwoPort):
    def complete_roles(self, roles):
        r1, r2 = roles["1"], roles["2"]
        if r1 is not None and r2 is not None and r1 == r2:
            raise RoleConflict("a transformer sets the effort at one port and the flow at the other, "
                               f"but both its bonds have it setting the {'effort' if r1 == EFFORT else 'flow'}")
        if r1 is not None:
            return {"1": r1, "2": other(r1)}
        if r2 is not None:
            return {"1": other(r2), "2": r2}
        return dict(roles)

    def contribute(self, ports, names):
        p1, p2, m = ports["1"], ports["2"], self._m
        if p1.role == EFFORT:   # e2 in -> e1 = m e2; f1 in -> f2 = m f1
            return Contribution(defs=[(p1.e, m * p2.e), (p2.f, p2.sign * m * p1.flow)])
        return Contribution(defs=[(p2.e, p1.e / m), (p1.f, p1.sign * p2.flow / m)])


class _Gyrator(_TwoPort):
    _symbol = "r"

    def complete_roles(self, roles):
        r1, r2 = roles["1"], roles["2"]
        if r1 is not None and r2 is not None and r1 != r2:
            raise RoleConflict("a gyrator sets the effort at both ports or the flow at both, "
                               "but its bonds disagree")
        known = r1 if r1 is not None else r2
        return {"1": known, "2": known} if known is not None else dict(roles)

    def contribute(self, ports, names):
        p1, p2, r = ports["1"], ports["2"], self._m
        if p1.role == EFFORT:   # flows in: e1 = r f2, e2 = r f1
            return Contribution(defs=[(p1.e, r * p2.flow), (p2.e, r * p1.flow)])
        return Contribution(defs=[(p2.f, p2.sign * p1.e / r), (p1.f, p1.sign * p2.e / r)])


class TF(_Transformer):
    """Transformer with a constant modulus (a parameter named after the element)."""

    kind = "TF"


class MTF(_Transformer):
    """Modulated transformer: modulus is an expression (e.g. ``"r*cos(q_psi)"``)."""

    kind = "MTF"


class GY(_Gyrator):
    """Gyrator with a constant modulus (a parameter named after the element)."""

    kind = "GY"


class MGY(_Gyrator):
    """Modulated gyrator: modulus is an expression."""

    kind = "MGY"


