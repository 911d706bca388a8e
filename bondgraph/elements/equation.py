"""Equation-defined elements, for pseudo-bond graphs and anything the
standard elements do not cover (pneumatic chambers, thermal nodes, sampled
friction laws).

The element declares its ports (with natural power direction), which
variable it sets at each port and by which expression, its states with
their rate equations, and optionally held (discrete) variables with their
update rule and the fixed step it needs.  Inside its expressions the port
variables are ``e_<port>`` and ``f_<port>`` (flow in the port's natural
direction), besides every graph-wide name.

Example: a pneumatic chamber with a pressure / mass-flow port ``pn`` and a
force / velocity port ``mech`` (contraction velocity ``f_mech`` out)::

    EquationElement(
        "chamber",
        ports={"pn": "in", "mech": "out"},
        outputs={"e_pn": "P", "e_mech": "P*A"},
        states={"P": "k*Rg*T*f_pn/(A*x) - k*P*(-A*f_mech)/(A*x)"},
        ...)
"""
from __future__ import annotations

import math

from ..errors import DerivationError
from ..guards import Guard, guard_from_dict
from ..symbols import sym
from .base import EFFORT, FLOW, Contribution, Element, HeldDecl, RoleConflict, StateDecl, param_dict

__all__ = ["EquationElement"]


class EquationElement(Element):
    """An element defined by its equations.

    Parameters
    ----------
    name : str
        Element name.
    ports : mapping str -> {"in", "out"}
        Port names and their natural power direction.  Empty for an element that owns states
        only and takes no bond: a sensor's or a controller's own dynamics, whose rates read the
        graph's names (:meth:`~bondgraph.editing.GraphEditing.sense_output`).
    outputs : mapping str -> expression
        ``"e_<port>"`` or ``"f_<port>"`` for each port: which variable the
        element sets there, and its value.
    states : mapping str -> expression, optional
        State name -> rate ``d(state)/dt``.
    initial : mapping str -> float, optional
        Initial state (and held) values.
    units : mapping str -> str, optional
        Units of states and held variables.
    held : mapping str -> expression, optional
        Discrete variables: name -> update rule, evaluated at the start of
        every integration sub-step (``h_step`` is the sub-step, s) and held
        constant over it.
    fixed_step : float, optional
        Largest integration sub-step the element honours, s.  Required when
        `held` is given.
    params : mapping or list of Param, optional
        Parameters the expressions use.
    locals : mapping str -> expression, optional
        Named intermediate quantities (a muscle's volume and force), in
        evaluation order; each may use the port variables, the graph's names
        and the earlier locals, and every other expression may use them.
        They appear as ``<element>.<name>`` in the equations' ordered
        assignments (:attr:`StateEquations.assignments`).
    guards : sequence of Guard, optional
        Physical-domain conditions (:mod:`bondgraph.guards`) over the
        graph's names, e.g. a chamber volume that must stay positive.
    """

    kind = "Eq"

    def __init__(self, name: str, *, ports, outputs, states=None, initial=None, units=None,
                 held=None, fixed_step: float | None = None, params=None, descriptions=None,
                 locals=None, guards=None, description: str = ""):
        super().__init__(name, description=description)
        self._set_locals(locals)
        ports = dict(ports)
        bad = {p: d for p, d in ports.items() if d not in ("in", "out") or not str(p).isidentifier()}
        if bad or not (ports or states):
            raise DerivationError(f"Eq {name!r}: ports must map identifiers to 'in' or 'out', got {bad or ports} "
                                  "(an element without ports must own states)", element=name)
        roles = {}
        for key in outputs:
            kind, _, port = str(key).partition("_")
            if kind not in ("e", "f") or port not in ports:
                raise DerivationError(
                    f"Eq {name!r}: output {key!r} must be e_<port> or f_<port> with a port among "
                    f"{', '.join(ports)}", element=name)
            if port in roles:
                raise DerivationError(f"Eq {name!r}: port {port} has two outputs; a port sets its "
                                      "effort or its flow, not both", element=name)
            roles[port] = EFFORT if kind == "e" else FLOW
        missing = [p for p in ports if p not in roles]
        if missing:
            raise DerivationError(f"Eq {name!r}: no output (e_<port> or f_<port>) for port(s) "
                                  f"{', '.join(missing)}", element=name)
        if held and fixed_step is None:
            raise DerivationError(f"Eq {name!r}: held variables need fixed_step=", element=name)
        if fixed_step is not None and (isinstance(fixed_step, bool) or not isinstance(fixed_step, (int, float))
                                       or not math.isfinite(fixed_step) or fixed_step <= 0):
            raise DerivationError(f"Eq {name!r}: fixed_step must be a positive number of seconds",
                                  element=name)
        self.ports = tuple(ports)
        self.directions = ports
        self.outputs = dict(outputs)
        self.roles = roles
        self.states = dict(states or {})
        self.held = dict(held or {})
        self.initial = {k: float(v) for k, v in (initial or {}).items()}
        self.units = dict(units or {})
        self.descriptions = dict(descriptions or {})
        self._fixed_step = None if fixed_step is None else float(fixed_step)
        self.params = param_dict(params, f"Eq {name!r}")
        self._guards = [g if isinstance(g, Guard) else guard_from_dict(k, g)
                        for k, g in (guards.items() if isinstance(guards, dict) else
                                     ((None, g) for g in (guards or ())))]
        unknown = [k for k in list(self.initial) + list(self.units) + list(self.descriptions)
                   if k not in self.states and k not in self.held]
        if unknown:
            raise DerivationError(f"Eq {name!r}: initial/units/descriptions given for "
                                  f"{', '.join(sorted(set(unknown)))}, "
                                  "which are neither states nor held variables", element=name)

    @property
    def fixed_step(self):
        return self._fixed_step

    def parameters(self):
        return list(self.params.values())

    def guards(self):
        return list(self._guards)

    def declared_states(self):
        return [(s, self.units.get(s, ""), self.initial.get(s, 0.0),
                 self.descriptions.get(s, f"state of {self.name}")) for s in self.states]

    def declared_held(self):
        return [(s, self.units.get(s, ""), self.initial.get(s, 0.0),
                 self.descriptions.get(s, f"held variable of {self.name}")) for s in self.held]

    def _placeholders(self) -> dict:
        """Stand-ins for the port variables, replaced by the bond variables in :meth:`contribute`."""
        names = {}
        for p in self.ports:
            names[f"e_{p}"] = sym(f"{self.name}.e_{p}")
            names[f"f_{p}"] = sym(f"{self.name}.f_{p}")
        return names

    def prepare(self, names):
        local = dict(names)
        local.update(self._placeholders())
        local = self._parse_locals(local)
        self._outputs = {key: self._expr(text, local, f"output {key}") for key, text in self.outputs.items()}
        self._rates = {s: self._expr(text, local, f"rate of {s}") for s, text in self.states.items()}
        self._updates = {v: self._expr(text, local, f"update of {v}") for v, text in self.held.items()}

    def fixed_roles(self):
        return dict(self.roles)

    def complete_roles(self, roles):
        for port, role in roles.items():
            if role is not None and role != self.roles[port]:
                word = "effort" if self.roles[port] == EFFORT else "flow"
                raise RoleConflict(f"it sets the {word} at port {port}, but so does the other end of the bond")
        return dict(self.roles)

    def contribute(self, ports, names):
        actual = {}
        for p, pv in ports.items():
            actual[sym(f"{self.name}.e_{p}")] = pv.e
            actual[sym(f"{self.name}.f_{p}")] = pv.flow
        out = Contribution(locals=[(s, e.xreplace(actual)) for s, e in self._local_defs])
        for key, value in self._outputs.items():
            kind, _, port = key.partition("_")
            pv = ports[port]
            value = value.xreplace(actual)
            out.defs.append((pv.e, value) if kind == "e" else (pv.f, pv.sign * value))
        for state, rate in self._rates.items():
            out.states.append(StateDecl(names[state], rate.xreplace(actual), self.initial.get(state, 0.0),
                                        self.units.get(state, ""),
                                        self.descriptions.get(state, f"state of {self.name}"), (self.name, state)))
        for var, update in self._updates.items():
            out.held.append(HeldDecl(names[var], update.xreplace(actual), self.initial.get(var, 0.0),
                                     self.units.get(var, ""),
                                     self.descriptions.get(var, f"held variable of {self.name}"), (self.name, var)))
        return out

    def _spec(self):
        spec = {"ports": dict(self.directions), "outputs": {k: str(v) for k, v in self.outputs.items()}}
        if self.states:
            spec["states"] = {k: str(v) for k, v in self.states.items()}
        if self.held:
            spec["held"] = {k: str(v) for k, v in self.held.items()}
            spec["fixed_step"] = self._fixed_step
        elif self._fixed_step is not None:
            spec["fixed_step"] = self._fixed_step
        for key in ("initial", "units", "descriptions"):
            if getattr(self, key):
                spec[key] = dict(getattr(self, key))
        if self.params:
            spec["params"] = {k: p.to_dict() for k, p in self.params.items()}
        if self.locals:
            spec["locals"] = {k: str(v) for k, v in self.locals.items()}
        if self._guards:
            spec["guards"] = {g.name: g.to_dict() for g in self._guards}
        return spec
