"""Truth plants of the generalisation benchmark: hand-written right-hand sides.

A :class:`TruthPlant` is a plant written directly as numpy state equations,
independently of the bond-graph code and of the diagnosis catalogue (it
imports neither), beside the name of the nominal library model it mirrors.
With no effect, its outputs equal the nominal model's (a test checks every
plant against ``bondgraph.numerics.simulate`` of its nominal model); a concealed effect
enters through one of four doors:

* ``extra`` -- an effort added at a 1-junction or a flow added at a
  0-junction, keyed by the junction's element name in the nominal graph
  (friction, a constant load, a leak, a changed spring law, an end stop); a
  storage element on a 0-junction changes the junction's effort itself, so a
  changed law there is an effort added to the element's law, keyed by the
  element's name (``extra["C1"]``: an oil volume's cubic stiffness);
* a plant-specific law hook (:attr:`TruthPlant.laws`): some effects change a
  constitutive law that is not a junction sum (a chamber's heat exchange);
* the inputs before the plant (actuator saturation, delay, lag: done by the
  effect, see :mod:`diagnosis.benchmark.effects`);
* the outputs after the plant (sensor offset, gain, range).

Sign convention of ``extra``: the effort (1-junction) or flow (0-junction)
that the effect puts INTO the junction, i.e. it adds to the sum that drives
the junction's storage.  Friction at a 1-junction of velocity ``v`` is
``extra = -F(v)``; a leak out of a 0-junction at pressure ``p`` is
``extra = -Q(p)``.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

__all__ = ["InputSpec", "OutputSpec", "JunctionSpec", "StorageSpec", "TruthPlant", "TruthPlantError",
           "UnknownTruthName"]


class TruthPlantError(ValueError):
    """A truth plant used wrongly (an unknown integration method).  The truth plants stand
    apart from the project's code, its error classes included."""


class UnknownTruthName(TruthPlantError, KeyError):
    """A junction, storage or plant name a truth plant does not have."""

    def __str__(self) -> str:   # KeyError would quote the message
        return Exception.__str__(self)


@dataclass(frozen=True)
class InputSpec:
    """One input: its nominal-model name, SI unit, command range and DAC resolution.

    ``hold`` is the (shortest, longest) time a random level is held, s: long
    enough for the plant to respond, short enough to excite its dynamics.
    ``ambient`` is the value the input rests at (pam valves: 5 V closed).
    ``load_at`` names the junction where the input's source acts, linearly in it (a force on
    its mass, a pump's flow into its tank, a heater's power into its block): an offset of the
    input is there a constant load, and the two are one answer (``""``: none, as a valve's
    voltage through its nonlinear flow law).
    ``profile(t, rng)``, when given, draws the command instead of random held
    levels (an imposed motion that must be smooth, such as a rod's strokes).
    """

    name: str
    unit: str
    low: float
    high: float
    quantum: float
    hold: tuple[float, float]
    ambient: float = 0.0
    profile: Callable | None = None
    load_at: str = ""


@dataclass(frozen=True)
class OutputSpec:
    """One measured output: nominal-model name and SI unit."""

    name: str
    unit: str


@dataclass(frozen=True)
class JunctionSpec:
    """A junction of the nominal graph where an effort (1) or flow (0) may be added.

    ``kind`` is ``"1"`` (common flow: ``signals[name]`` is that flow, e.g. a
    velocity) or ``"0"`` (common effort: ``signals[name]`` is that effort,
    e.g. a pressure).  ``ambient`` is the effort a leak flows towards (0 for
    gauge pressures, the atmosphere for absolute ones).  ``pressures`` names
    the signals that may modulate a friction law there (pneumatic plants);
    ``modulators`` the inputs whose level may set a friction there through a
    lag (a damper's coil voltage, a seal's switched pressure).
    ``equivalent`` lists junctions no recording can tell apart from this one
    (rigidly geared through a TF: one degree of freedom).  ``law``: not a junction of the
    nominal graph but a constitutive law whose bond ends at no junction (the diagnosis's
    ``law <name>`` place, :mod:`diagnosis.law_places`): ``name`` is the element owning the law,
    ``signals[name]`` the flow of its bond and ``extra[name]`` an effort added to its law.
    ``algebraic`` (a 1-junction): its flow is no state but set by a law of the effort across it
    (an orifice), so an effort added there changes the flow it depends on: the plant's
    ``signals(x, u, extra)`` gives the flow under an added effort, and the truth solves the two
    together (:func:`diagnosis.benchmark.simulate.effect_extra`).
    ``one_way`` (a 1-junction): its flow keeps one sign in every recording the plant makes (a
    tank's outflow to a lower one, a pump's pipe), where a law that depends on the direction of
    the flow is one law of that flow, which no recording can tell from it.
    ``relative`` (a 1-junction): its flow is the rate of a deflection between two bodies (a shaft's
    twist), whose integral is no position a load could repeat with.
    """

    name: str
    kind: str
    domain: str
    ambient: float = 0.0
    pressures: tuple[str, ...] = ()
    equivalent: tuple[str, ...] = ()
    modulators: tuple[str, ...] = ()
    law: bool = False
    algebraic: bool = False
    one_way: bool = False
    relative: bool = False

    @property
    def place(self) -> str:
        """The place as the diagnosis's report names it."""
        return f"{'law' if self.law else 'junction'} {self.name}"


@dataclass(frozen=True)
class StorageSpec:
    """A storage element (C) of the nominal graph whose law an effect may change.

    ``junction`` is the junction where a change of its effort acts (the
    1-junction whose velocity loads a spring, or the 0-junction of a tank);
    ``signals[name]`` is its content (displacement, twist, volume) and
    ``stiffness`` its nominal linear coefficient (effort per content) when the
    law is linear, else ``None``.  ``sign``: +1 when an added spring effort
    ``e(q)`` enters ``junction`` as ``-e(q)`` (a spring opposing the motion that
    loads it), -1 when it enters as ``+e(q)``.  ``sensed``: the outputs that read this
    element's effort (a torque sensor on a series spring, a pressure sensor on an oil volume, a
    capacitor's voltage): a change of its law is in their reading too.
    """

    name: str
    junction: str
    stiffness: float | None
    sign: float = 1.0
    content_range: tuple[float, float] | None = None
    sensed: tuple[str, ...] = ()


@dataclass(frozen=True)
class InductorSpec:
    """An electrical I element of the nominal graph whose core may saturate.

    ``junction`` is its 1-junction, whose flow (its current) the plant's state carries;
    ``extra[name]`` is the relative rise of its inverse differential inductance there,
    ``L / L_d(i) - 1``: the right-hand side multiplies that current's rate by ``1 + extra[name]``.
    """

    name: str
    junction: str


@dataclass
class TruthPlant:
    """A plant as hand-written state equations, mirroring a nominal library model.

    Parameters
    ----------
    name : str
        Benchmark name of the plant.
    model : str
        The nominal model the diagnosis is given (a ``plants.library`` name).
    inputs, outputs : tuple
        :class:`InputSpec` / :class:`OutputSpec`, in the nominal model's names and units.
    states : tuple of str
        Names of the truth states (documentation; any order).
    x0 : ndarray
        Initial state (equal to the nominal model's initial state).
    rhs : callable ``(x, u, extra) -> dx``
        ``x`` state (n,), ``u`` dict input name -> value, ``extra`` dict junction
        name -> added effort/flow (missing keys are 0).
    signals : callable ``(x, u) -> dict``
        Local variables an effect may need: the flow of each 1-junction and the
        effort of each 0-junction in :attr:`junctions` (by junction name), each
        storage's content (by storage name), pressures (by name).  With an
        ``algebraic`` junction it also takes ``extra`` (``(x, u, extra)``): the
        flows under the efforts added there.
    measure : callable ``(x, u) -> dict``
        The outputs, nominal-model names, SI.
    junctions, storages, inductors : tuple
        Where effects may act (:class:`JunctionSpec`, :class:`StorageSpec`, :class:`InductorSpec`).
    rate : float, Hz
        Sample rate of its recordings.
    duration : float, s
        Length of its recordings.
    substeps : int
        RK4 sub-steps per sample (``method="rk4"``).
    method : {"rk4", "lsoda"}
        ``"lsoda"`` for stiff plants (scipy, ``max_step`` one sample).
    drifts : bool
        The nominal model integrates its inputs (no restoring force): an
        unmodelled effect makes its simulation drift away from the recording.
    laws : dict
        Plant-specific effect hooks (``name -> callable``), documented per plant.
    hold : callable ``(x, u, extra, h) -> dict``, optional
        Held (discrete) variables of a fixed-step law (``method="rk4"`` only):
        evaluated once at the start of every RK4 sub-step of length ``h`` (s)
        and passed to ``rhs`` inside ``u`` over that sub-step (the PAM joint's
        Kikuuwe friction).  ``None``: the plant has none.
    nominal_x0 : dict, optional
        The nominal graph's initial state (its state names -> SI values) that
        equals :attr:`x0`, when :attr:`x0` is not the library graph's default
        (pass it as ``x0`` to ``bondgraph.numerics.simulate``); ``None``: the default.
    feedthrough : bool
        ``measure`` takes a third argument, ``extra``: an output is a junction
        effort that an effect changes algebraically, with no storage between
        (the load cell on the massless piston of the pneumatic cylinder).
    """

    name: str
    model: str
    inputs: tuple[InputSpec, ...]
    outputs: tuple[OutputSpec, ...]
    states: tuple[str, ...]
    x0: np.ndarray
    rhs: Callable
    signals: Callable
    measure: Callable
    junctions: tuple[JunctionSpec, ...] = ()
    storages: tuple[StorageSpec, ...] = ()
    inductors: tuple[InductorSpec, ...] = ()
    rate: float = 100.0
    duration: float = 20.0
    substeps: int = 4
    method: str = "rk4"
    drifts: bool = False
    laws: dict = field(default_factory=dict)
    description: str = ""
    hold: Callable | None = None
    feedthrough: bool = False
    nominal_x0: dict | None = None

    def junction(self, name: str) -> JunctionSpec:
        for j in self.junctions:
            if j.name == name:
                return j
        raise UnknownTruthName(f"plant {self.name}: no junction {name!r}; it has {[j.name for j in self.junctions]}")

    def inductor(self, name: str) -> InductorSpec:
        for s in self.inductors:
            if s.name == name:
                return s
        raise UnknownTruthName(f"plant {self.name}: no inductor {name!r}; it has {[s.name for s in self.inductors]}")

    def junction_at(self, door: str, name: str) -> str:
        """The junction an effect at (`door`, `name`) acts at: a storage's or an inductor's, else
        `name` itself (a junction; an input's or output's name, which is none)."""
        if door == "storage":
            return self.storage(name).junction
        if door == "inductor":
            return self.inductor(name).junction
        return name

    def storage(self, name: str) -> StorageSpec:
        for s in self.storages:
            if s.name == name:
                return s
        raise UnknownTruthName(f"plant {self.name}: no storage {name!r}; it has {[s.name for s in self.storages]}")
