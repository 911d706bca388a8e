"""Resistive element R (linear or nonlinear, either causality where invertible)."""
from __future__ import annotations

import sympy as sp

from ..errors import DerivationError
from ..law_inverses import unique_inverse
from ..symbols import sym
from .base import EFFORT, FLOW, Contribution, Element, RoleConflict, element_param, param_dict, unit_of

__all__ = ["R"]


class R(Element):
    """Resistor: ``e = value * f``, or a nonlinear law in either direction.

    Parameters
    ----------
    name : str
        Element name; also its parameter's name when `value` is given.
    value : float, optional
        Resistance (N s/m, Ohm...).
    effort : str or sympy.Expr, optional
        Effort as a function of the flow into the element, written with ``f``.
    flow : str or sympy.Expr, optional
        Flow into the element as a function of the effort, written with ``e``.
    params : mapping, optional
        Parameters the law uses.
    domain : str
        Energy domain for default units.

    Notes
    -----
    A law given one way is inverted symbolically when that has a unique
    solution (then SCAP may choose either causality); otherwise the element's
    causality is fixed by the law given, which may create an algebraic loop.
    """

    kind = "R"

    def __init__(self, name: str, value=None, *, effort=None, flow=None, params=None,
                 domain: str = "generic", unit: str | None = None, description: str = ""):
        super().__init__(name, description=description)
        if sum(v is not None for v in (value, effort, flow)) != 1:
            raise DerivationError(f"R {name!r}: give exactly one of value, effort= or flow=", element=name)
        self.domain = domain
        self.params = param_dict(params, f"R {name!r}")
        self.value = None if value is None else element_param(
            value, name, unit, unit_of(domain, "resistance"), f"resistance of {name}", min=0.0)
        if self.value is not None:
            self.params[name] = self.value
        self.effort_law, self.flow_law = effort, flow
        self._e = sym(f"{name}.e")   # placeholders for the port variables
        self._f = sym(f"{name}.f")
        self._laws: dict[str, sp.Expr] = {}

    def parameters(self):
        return list(self.params.values())

    def prepare(self, names):
        local = dict(names)
        local["e"], local["f"] = self._e, self._f
        if self.value is not None:
            r = names[self.name]
            self._laws = {EFFORT: r * self._f, FLOW: self._e / r}
            return
        given, known, unknown = ((EFFORT, self._f, self._e) if self.effort_law is not None
                                 else (FLOW, self._e, self._f))
        law = self._expr(self.effort_law if given == EFFORT else self.flow_law, local, "law")
        self._laws = {given: law}
        inverse = unique_inverse(law, unknown, known)   # switched laws are not inverted
        if inverse is not None:
            self._laws[FLOW if given == EFFORT else EFFORT] = inverse

    def fixed_roles(self):
        if len(self._laws) == 1:
            return {"": next(iter(self._laws))}
        return None

    def complete_roles(self, roles):
        fixed = self.fixed_roles()
        if fixed and roles[""] is not None and roles[""] != fixed[""]:
            word = "effort" if fixed[""] == EFFORT else "flow"
            raise RoleConflict(f"its law gives the {word} only (not invertible), "
                               "but the other end of the bond sets it")
        return dict(fixed) if fixed else dict(roles)

    def contribute(self, ports, names):
        port = ports[""]
        law = self._laws.get(port.role)
        if law is None:  # pragma: no cover - causality never assigns a role without a law
            raise DerivationError(f"R {self.name!r} has no law for role {port.role!r}", element=self.name)
        if port.role == EFFORT:
            return Contribution(defs=[(port.e, law.xreplace({self._f: port.flow}))])
        return Contribution(defs=[(port.f, port.sign * law.xreplace({self._e: port.e}))])

    def _spec(self):
        spec = {"domain": self.domain}
        if self.value is not None:
            spec["value"] = self.value.value
            spec["unit"] = self.value.unit
        elif self.effort_law is not None:
            spec["effort"] = str(self.effort_law)
        else:
            spec["flow"] = str(self.flow_law)
        extra = {k: p.to_dict() for k, p in self.params.items() if p is not self.value}
        if extra:
            spec["params"] = extra
        return spec

