"""Multiport C and I fields (integral causality on every port).

A C-field with ports ``a, b`` has states ``q_<name>_a, q_<name>_b``
(``dq_i/dt = f_i``) and efforts ``e_i = Phi_i(q)``, given per port or as the
gradient of a stored energy ``E(q)`` (``e_i = dE/dq_i``, which makes the
field reciprocal by construction).  An I-field is the dual: momenta
``p_<name>_i`` with ``dp_i/dt = e_i`` and flows ``f_i = Phi_i(p)``.
In expressions the element's own states may be written ``q_a``, ``q_b``
(``p_a``... for an I-field).
"""
from __future__ import annotations

import sympy as sp

from ..errors import DerivationError
from .base import EFFORT, FLOW, Contribution, Element, RoleConflict, StateDecl, param_dict, unit_of

__all__ = ["CField", "IField"]


class _Field(Element):
    _role = EFFORT
    _prefix = "q"
    _quantity = "displacement"

    def __init__(self, name: str, ports, *, laws=None, energy=None, params=None, initial=None,
                 domain: str = "generic", description: str = ""):
        super().__init__(name, description=description)
        ports = tuple(ports)
        if len(ports) < 2 or len(set(ports)) != len(ports) or not all(
                isinstance(p, str) and p.isidentifier() for p in ports):
            raise DerivationError(f"{self.kind} {name!r}: needs at least two distinct port names "
                                  f"(identifiers), got {ports!r}", element=name)
        if (laws is None) == (energy is None):
            raise DerivationError(f"{self.kind} {name!r}: give laws= (one per port) or energy=, not both",
                                  element=name)
        if laws is not None and set(laws) != set(ports):
            raise DerivationError(f"{self.kind} {name!r}: laws given for {sorted(laws)}, ports are "
                                  f"{sorted(ports)}", element=name)
        unknown = sorted(set(initial or {}) - set(ports))
        if unknown:
            raise DerivationError(f"{self.kind} {name!r}: initial values for {', '.join(unknown)}, which are not "
                                  f"ports (ports: {', '.join(ports)})", element=name)
        self.ports = ports
        self.directions = {p: "in" for p in ports}
        self.laws, self.energy = (dict(laws) if laws is not None else None), energy
        self.params = param_dict(params, f"{self.kind} {name!r}")
        self.initial = {p: float((initial or {}).get(p, 0.0)) for p in ports}
        self.domain = domain
        self._parsed: dict[str, sp.Expr] = {}

    def state_name(self, port: str) -> str:
        return f"{self._prefix}_{self.name}_{port}"

    def parameters(self):
        return list(self.params.values())

    def declared_states(self):
        unit = unit_of(self.domain, self._quantity)
        return [(self.state_name(p), unit, self.initial[p], f"{self._quantity} at port {p} of {self.name}")
                for p in self.ports]

    def prepare(self, names):
        local = dict(names)
        states = {p: names[self.state_name(p)] for p in self.ports}
        for p, s in states.items():
            local[f"{self._prefix}_{p}"] = s
        if self.laws is not None:
            self._parsed = {p: self._expr(self.laws[p], local, f"law of port {p}") for p in self.ports}
        else:
            energy = self._expr(self.energy, local, "energy")
            self._parsed = {p: sp.diff(energy, states[p]) for p in self.ports}

    def fixed_roles(self):
        return {p: self._role for p in self.ports}

    def complete_roles(self, roles):
        for port, role in roles.items():
            if role is not None and role != self._role:
                raise RoleConflict(
                    f"port {port} would be in derivative causality; "
                    "fields support integral causality on every port only")
        return self.fixed_roles()

    def contribute(self, ports, names):
        out = Contribution()
        unit = unit_of(self.domain, self._quantity)
        for p in self.ports:
            pv = ports[p]
            x = names[self.state_name(p)]
            if self._role == EFFORT:
                out.defs.append((pv.e, self._parsed[p]))
                rate = pv.flow
            else:
                out.defs.append((pv.f, pv.sign * self._parsed[p]))
                rate = pv.e
            out.states.append(StateDecl(x, rate, self.initial[p], unit,
                                        f"{self._quantity} at port {p} of {self.name}", (self.name, p)))
        return out

    def _spec(self):
        spec = {"ports": list(self.ports), "domain": self.domain, "initial": dict(self.initial)}
        if self.laws is not None:
            spec["laws"] = {p: str(v) for p, v in self.laws.items()}
        else:
            spec["energy"] = str(self.energy)
        if self.params:
            spec["params"] = {k: v.to_dict() for k, v in self.params.items()}
        return spec


class CField(_Field):
    """Multiport capacitive field (see the module docstring)."""

    kind = "CField"


class IField(_Field):
    """Multiport inertial field (see the module docstring)."""

    kind = "IField"
    _role = FLOW
    _prefix = "p"
    _quantity = "momentum"
