"""Truth models: a nominal library graph plus one concealed effect, written by hand.

Written independently of the diagnosis catalogue (it imports none of it).
Where the effect sits decides how it is added (see :class:`diagnosis.place.Place`):

* ``junction``: a bond-graph element bonded to the junction -- an ``R`` with a
  nonlinear effort law at a 1-junction (friction: extra effort), an ``R`` with
  a flow law at a 0-junction (leak: extra flow), a ``C`` with a cubic law
  (hardening spring), or a small network (an RC valve driver for a valve lag).
* ``input``: the recorded command is transformed before it reaches the model
  (actuator saturation, transport delay) -- exact on zero-order-hold tables.
* ``output``: the model output is transformed before it is recorded (sensor
  gain, sensor offset).

Each effect is a frozen dataclass holding its parameters (SI); with its
``neutral()`` parameters the truth model equals the nominal model.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from bondgraph import BondGraph
from bondgraph.elements import C, MSf, One, R, Se
from bondgraph.params import Param

from ..place import Place
from ..errors import UnknownCaseError

__all__ = ["EffectParam", "Effect", "ResistiveEffect", "CubicSpring", "PamValveLag",
           "InputSaturation", "InputDelay", "SensorGain", "SensorOffset", "copy_graph"]


@dataclass(frozen=True)
class EffectParam:
    """One true parameter of a concealed effect (SI value, its unit and meaning)."""

    name: str
    value: float
    unit: str
    description: str


@dataclass(frozen=True)
class Effect:
    """Base class: a concealed effect of one `kind` at one `place`.

    Subclasses override :meth:`graph` (junction effects), :meth:`inputs`
    (actuator effects) or :meth:`outputs` (sensor effects); the defaults are
    the identity.
    """

    kind: str
    place: Place
    params: tuple[EffectParam, ...]

    def value(self, name: str) -> float:
        """The SI value of parameter `name`."""
        for p in self.params:
            if p.name == name:
                return p.value
        raise UnknownCaseError(f"{self.kind}: no parameter {name!r}; it has {[p.name for p in self.params]}")

    def with_values(self, **values: float) -> "Effect":
        """The same effect with some parameter values replaced (SI)."""
        unknown = set(values) - {p.name for p in self.params}
        if unknown:
            raise UnknownCaseError(f"{self.kind}: no parameter(s) {sorted(unknown)}")
        return replace(self, params=tuple(replace(p, value=float(values.get(p.name, p.value)))
                                          for p in self.params))

    def neutral(self) -> "Effect":
        """The effect with parameters that make the truth model equal the nominal one."""
        return self.with_values(**self._neutral_values())

    def _neutral_values(self) -> dict:
        raise NotImplementedError  # every concrete effect says what switches it off

    def graph(self, nominal: BondGraph) -> BondGraph:
        """The truth graph (default: the nominal graph itself)."""
        return nominal

    def structure(self):
        """What decides the truth graph's equations, the parameter values aside (hashable);
        ``None`` when the truth graph is the nominal one.  Two effects of the same structure
        share one derivation and differ only by :meth:`simulation_params`."""
        return None

    def simulation_params(self) -> dict[str, float]:
        """Parameter values (SI) to pass to ``simulate(params=...)`` for the truth graph."""
        return {}

    def _blank(self) -> "Effect":
        return replace(self, params=tuple(replace(p, value=1.0) for p in self.params))

    def inputs(self, t: np.ndarray, commands: dict) -> dict:
        """Input tables ``name -> (times, values)`` the truth model sees (default: the commands)."""
        return {name: (np.asarray(t, float), np.asarray(u, float)) for name, u in commands.items()}

    def outputs(self, outputs: dict) -> dict:
        """Recorded outputs from the model outputs (default: unchanged)."""
        return dict(outputs)


def _params(effect: Effect) -> dict[str, Param]:
    return {p.name: Param(p.name, p.value, p.unit, p.description) for p in effect.params}


@dataclass(frozen=True)
class ResistiveEffect(Effect):
    """An ``R`` element bonded to the junction ``place.name``.

    ``law`` is its effort as a function of its flow ``f`` (1-junction: an extra
    effort, e.g. a friction torque) or, with ``flow_law=True``, its flow as a
    function of its effort ``e`` (0-junction: an extra flow, e.g. a leak); the
    law may use the effect's parameters and any name of the graph (states,
    parameters).  ``zero`` lists the parameters that, set to 0, remove it.
    """

    law: str = ""
    flow_law: bool = False
    domain: str = "generic"
    zero: tuple[str, ...] = ()

    def _neutral_values(self) -> dict:
        return {name: 0.0 for name in self.zero}

    def structure(self):
        return self._blank()

    def simulation_params(self):
        return {p.name: p.value for p in self.params}

    def graph(self, nominal: BondGraph) -> BondGraph:
        name = f"{self.kind}_{self.place.name}"
        law = {"flow": self.law} if self.flow_law else {"effort": self.law}
        nominal.add(R(name, params=_params(self), domain=self.domain,
                      description=f"concealed {self.kind}", **law))
        nominal.connect(self.place.name, name)
        return nominal


@dataclass(frozen=True)
class CubicSpring(Effect):
    """Hardening spring: a ``C`` with ``e = k3 q^3`` on the 1-junction (parallel to the linear
    spring there, same displacement when both start relaxed), parameter ``k3``."""

    domain: str = "generic"

    def _neutral_values(self) -> dict:
        return {"k3": 0.0}

    def structure(self):
        return self._blank()

    def simulation_params(self):
        return {"k3": self.value("k3")}

    def graph(self, nominal: BondGraph) -> BondGraph:
        name = f"{self.kind}_{self.place.name}"
        nominal.add(C(name, law="k3*q**3", params=_params(self), domain=self.domain,
                      description="concealed cubic (hardening) stiffness"))
        nominal.connect(self.place.name, name)
        return nominal


@dataclass(frozen=True)
class PamValveLag(Effect):
    """First-order lag ``tau`` between the command ``u<i>`` and PAM valve ``i`` (its driver).

    Bond-graph form: the command drives a series RC network (``Se u<i>`` ->
    1-junction with ``R`` = tau / C and ``C``); the capacitor voltage
    ``e_<C>`` replaces ``u<i>`` in the valve law, eq. (5) of seed 000:
    :math:`\\tau \\dot u_v = u - u_v`.  ``tau = 0`` is the nominal model
    (handled by returning it unchanged: an RC with R = 0 is not a state).
    """

    c_drive: float = 1e-3      # F, capacitance of the driver network (only tau = R C matters)

    def _neutral_values(self) -> dict:
        return {"tau": 0.0}

    def structure(self):
        return None if self.value("tau") == 0.0 else self._blank()

    def simulation_params(self):
        tau = self.value("tau")
        return {} if tau == 0.0 else {f"valve{self.place.name[-1]}_driver_R": tau / self.c_drive}

    def graph(self, nominal: BondGraph) -> BondGraph:
        from plants.library.pam import valve_law
        tau = self.value("tau")
        if tau == 0.0:
            return nominal
        u = self.place.name
        i = u[-1]
        cap, res = f"valve{i}_driver_C", f"valve{i}_driver_R"
        new = copy_graph(nominal, replace={f"valve{i}": MSf(
            f"valve{i}", valve_law(f"e_{cap}", f"P_{i}"), domain="pneumatic",
            description=f"valve {i}, eq. (5), driven by the lagged voltage e_{cap}")}, drop_inputs=(u,))
        new.add(Se(f"{u}_source", input=u, domain="electrical", description=f"valve {i} command, V"))
        new.add(One(f"{u}_driver"))
        new.add(R(res, tau / self.c_drive, domain="electrical", description="driver resistance, tau / C"))
        new.add(C(cap, self.c_drive, domain="electrical", description="driver capacitance"))
        for tail, head in ((f"{u}_source", f"{u}_driver"), (f"{u}_driver", res), (f"{u}_driver", cap)):
            new.connect(tail, head)
        return new


@dataclass(frozen=True)
class InputSaturation(Effect):
    """The actuator delivers ``clip(u, -limit, limit)`` of the command ``u`` (parameter ``limit``)."""

    def _neutral_values(self) -> dict:
        return {"limit": np.inf}

    def inputs(self, t, commands):
        out = super().inputs(t, commands)
        times, u = out[self.place.name]
        limit = self.value("limit")
        out[self.place.name] = (times, np.clip(u, -limit, limit))
        return out


@dataclass(frozen=True)
class InputDelay(Effect):
    """The actuator applies the command ``delay`` seconds late: ``u_act(t) = u(t - delay)``
    (exact on a zero-order-hold table: its breakpoints move by `delay`; before the
    first one the first value holds, the rest state)."""

    def _neutral_values(self) -> dict:
        return {"delay": 0.0}

    def inputs(self, t, commands):
        out = super().inputs(t, commands)
        times, u = out[self.place.name]
        out[self.place.name] = (times + self.value("delay"), u)
        return out


@dataclass(frozen=True)
class SensorGain(Effect):
    """The sensor of output ``place.name`` reads ``gain`` times the true value."""

    def _neutral_values(self) -> dict:
        return {"gain": 1.0}

    def outputs(self, outputs):
        out = dict(outputs)
        out[self.place.name] = self.value("gain") * np.asarray(out[self.place.name])
        return out


@dataclass(frozen=True)
class SensorOffset(Effect):
    """The sensor of output ``place.name`` reads the true value plus ``offset``."""

    def _neutral_values(self) -> dict:
        return {"offset": 0.0}

    def outputs(self, outputs):
        out = dict(outputs)
        out[self.place.name] = np.asarray(out[self.place.name]) + self.value("offset")
        return out


def copy_graph(graph: BondGraph, *, replace: dict | None = None, drop_inputs=()) -> BondGraph:
    """A new graph with the same elements, bonds, parameters, inputs and outputs.

    Parameters
    ----------
    graph : BondGraph
    replace : dict str -> Element, optional
        Elements to put in place of the ones of the same name (same bonds).
    drop_inputs : iterable of str
        Declared (``add_input``) inputs to leave out (a source will provide them).
    """
    replace = dict(replace or {})
    unknown = set(replace) - set(graph.elements)
    if unknown:
        raise UnknownCaseError(f"copy_graph: {graph.name!r} has no element(s) {sorted(unknown)}")
    new = BondGraph(graph.name, description=graph.description)
    for p in graph.extra_params.values():
        new.add_parameter(p)
    for decl in graph.extra_inputs.values():
        if decl.name not in drop_inputs:
            new.add_input(decl.name, default=decl.default, unit=decl.unit, description=decl.description)
    for name, element in graph.elements.items():
        new.add(replace.get(name, element))
    for bond in graph.bonds.values():
        new.connect((bond.tail.element, bond.tail.port), (bond.head.element, bond.head.port),
                    name=bond.name)
    for out in graph.outputs.values():
        new.add_output(out.name, out.expression, unit=out.unit, description=out.description)
    return new

