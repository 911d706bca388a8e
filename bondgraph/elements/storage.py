"""Storage elements I and C (one-port, linear or nonlinear)."""
from __future__ import annotations

import sympy as sp

from ..errors import DerivationError
from .base import EFFORT, FLOW, Contribution, DerivativeDecl, Element, StateDecl, element_param, param_dict, unit_of

__all__ = ["I", "C"]


class _Storage(Element):
    _integral_role = FLOW
    _state_prefix = "p"
    _local = "p"             # local name of the energy variable in `law`
    _param_quantity = "inertance"
    _state_quantity = "momentum"
    _out_quantity = "flow"

    def __init__(self, name: str, value=None, *, law=None, params=None, state: str | None = None,
                 initial: float = 0.0, domain: str = "generic", unit: str | None = None,
                 description: str = ""):
        super().__init__(name, description=description)
        if (value is None) == (law is None):
            raise DerivationError(f"{self.kind} {name!r}: give exactly one of a value or a law", element=name)
        self.domain = domain
        self.state = state or f"{self._state_prefix}_{name}"
        self.initial = float(initial)
        self.params = param_dict(params, f"{self.kind} {name!r}")
        self.value = None if value is None else element_param(
            value, name, unit, unit_of(domain, self._param_quantity), f"{self._param_quantity} of {name}", min=0.0)
        if self.value is not None:
            self.params[name] = self.value
        self.law = law
        self._parsed = None

    def parameters(self):
        return list(self.params.values())

    def declared_states(self):
        return [(self.state, unit_of(self.domain, self._state_quantity), self.initial,
                 f"{self._state_quantity} of {self.kind} {self.name}")]

    def preferred_roles(self):
        return {"": self._integral_role}

    def prepare(self, names):
        x = names[self.state]
        if self.value is not None:
            self._parsed = self._linear_law(x, names[self.name])
        else:
            local = dict(names)
            local[self._local] = x
            self._parsed = self._expr(self.law, local, "law")

    def _linear_law(self, x, value):
        return x / value

    def _inverse(self, target: sp.Expr, names) -> sp.Expr:
        """The energy variable that makes the law's output equal `target`."""
        x = names[self.state]
        if self.value is not None:
            return target * names[self.name]
        w = sp.Dummy("w", real=True)
        solutions = sp.solve(sp.Eq(self._parsed, w), x)
        if len(solutions) != 1:
            raise DerivationError(
                f"{self.kind} {self.name!r} is in derivative causality, which needs the inverse of its law "
                f"{self._parsed}; found {len(solutions)} solutions for {x}", element=self.name)
        return solutions[0].xreplace({w: target})

    def contribute(self, ports, names):
        port = ports[""]
        x = names[self.state]
        if port.role == self._integral_role:
            return self._integral(port, x)
        bond_input = port.flow if self._integral_role == FLOW else port.e
        output = port.e if self._integral_role == FLOW else port.f
        factor = 1 if self._integral_role == FLOW else port.sign
        stored = self._inverse(bond_input, names)
        return Contribution(derivative=[DerivativeDecl(output, factor, stored, self.name, port.bond, self.state)])

    def _spec(self):
        spec = {"domain": self.domain, "state": self.state, "initial": self.initial}
        if self.value is not None:
            spec["value"] = self.value.value
            spec["unit"] = self.value.unit
        else:
            spec["law"] = str(self.law)
        extra = {k: p.to_dict() for k, p in self.params.items() if p is not self.value}
        if extra:
            spec["params"] = extra
        return spec


class I(_Storage):
    """Inertia: ``dp/dt = e``, ``f = Phi(p)`` (linear: ``f = p / value``).

    Parameters
    ----------
    name : str
        Element name; also the name of its parameter when `value` is given.
    value : float, optional
        Inertance (kg, kg m^2, H...).  Give this or `law`.
    law : str or sympy.Expr, optional
        Flow as a function of the momentum, written with ``p`` (or the state name).
    params : mapping, optional
        Parameters `law` uses.
    state : str, optional
        State name (default ``p_<name>``).
    initial : float
        Initial momentum.
    domain : str
        Energy domain for default units.
    """

    kind = "I"

    def _integral(self, port, x):
        rate = port.e
        state = StateDecl(x, rate, self.initial, unit_of(self.domain, "momentum"),
                          f"momentum of I {self.name}", (self.name, "p"))
        return Contribution(defs=[(port.f, port.sign * self._parsed)], states=[state])


class C(_Storage):
    """Compliance: ``dq/dt = f``, ``e = Phi(q)`` (linear: ``e = q / value``).

    Parameters
    ----------
    name : str
        Element name; also the name of its parameter when `value` or `stiffness` is given.
    value : float, optional
        Compliance (m/N, F, m^3/Pa...).
    stiffness : float, optional
        Alternative to `value`: ``e = stiffness * q``.
    law : str or sympy.Expr, optional
        Effort as a function of the displacement, written with ``q``.
    """

    kind = "C"
    _integral_role = EFFORT
    _state_prefix = "q"
    _local = "q"
    _param_quantity = "compliance"
    _state_quantity = "displacement"

    def __init__(self, name: str, value=None, *, stiffness=None, law=None, params=None,
                 state: str | None = None, initial: float = 0.0, domain: str = "generic",
                 unit: str | None = None, description: str = ""):
        self.stiffness_form = stiffness is not None
        if stiffness is not None:
            if value is not None:
                raise DerivationError(f"C {name!r}: give a compliance value or a stiffness, not both",
                                      element=name)
            self._param_quantity = "stiffness"
            value = stiffness
        super().__init__(name, value, law=law, params=params, state=state, initial=initial,
                         domain=domain, unit=unit, description=description)

    def _linear_law(self, x, value):
        return x * value if self.stiffness_form else x / value

    def _inverse(self, target, names):
        if self.value is not None and self.stiffness_form:
            return target / names[self.name]
        return super()._inverse(target, names)

    def _integral(self, port, x):
        state = StateDecl(x, port.flow, self.initial, unit_of(self.domain, "displacement"),
                          f"displacement of C {self.name}", (self.name, "q"))
        return Contribution(defs=[(port.e, self._parsed)], states=[state])

    def _spec(self):
        spec = super()._spec()
        if self.stiffness_form:
            spec["stiffness"] = spec.pop("value")
        return spec

