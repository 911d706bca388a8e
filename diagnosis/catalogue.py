"""The catalogue of candidate physics: what a model may be missing, by physical name.

Each :class:`Candidate` is one kind of effect (:data:`KINDS`) attached to one
:class:`~diagnosis.place.Place`, with fitted parameters (:class:`ParamSpec`:
guess and bounds scaled from the data) and fixed constants.
:meth:`Candidate.build` returns a NEW graph with the effect added as a proper
bond-graph element (R with a nonlinear law, C with a changed law, equation
element, 1-junction branch), an input transformation (the element reading the
input gets the lag / delay / saturation, with its extra states) or an output
transformation.  Candidate parameters are graph parameters, so a compiled
candidate is re-run with new values, and the graph saves to JSON and exports
to an FMU like any other.

Which kinds at which place (:func:`candidates`):

* 1-junction: ``coulomb_friction``, ``viscous_friction``, ``coulomb_viscous_friction``,
  ``stribeck_friction``, ``pressure_dependent_friction`` (one per pressure variable
  of the model), ``modulated_friction`` (one per input and per listed effort of
  another domain, :func:`~diagnosis.catalogue_modulated.modulating_signals`),
  ``hysteresis``, and for each C on it ``backlash``, ``nonlinear_stiffness``
  (with the C's own linear value refitted), ``saturation`` (end stops)
  (:mod:`diagnosis.catalogue_friction`, :mod:`diagnosis.catalogue_modulated`,
  :mod:`diagnosis.catalogue_storage`);
* 0-junction: ``leak``, ``heat_transfer`` (pneumatic / thermal only),
  ``nonlinear_stiffness`` and ``saturation`` (an overflow) for each C on it;
* 0- and 1-junction: ``constant_load`` (:mod:`diagnosis.catalogue_loads`);
* input: ``valve_lag``, ``transport_delay``, ``saturation``;
* output: ``saturation`` (the sensor's range), ``sensor_offset``, ``sensor_gain``
  (:mod:`diagnosis.catalogue_signals`).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from bondgraph.io_json import graph_from_dict

from .catalogue_common import ParamSpec, add_parameter
from .catalogue_friction import FRICTION_KINDS, build_friction, explain_friction, make_friction
from .catalogue_loads import LOAD_KINDS, build_load, explain_load, make_load
from .catalogue_modulated import (MODULATED_KINDS, build_modulated, explain_modulated, make_modulated,
                                  modulating_signals)
from .catalogue_scales import experiment_times, junction_scales
from .catalogue_signals import (INPUT_KINDS, OUTPUT_KINDS, build_signal, explain_signal, make_input,
                                make_output)
from .catalogue_storage import STORAGE_KINDS, build_storage, explain_storage, make_storage
from .place import Place
from .errors import DiagnosisError, UnknownNameError

__all__ = ["KINDS", "ParamSpec", "Candidate", "candidates"]

#: The vocabulary, in its order (issue 6's kinds, then constant_load, then issue 11's friction laws).
KINDS = ("coulomb_friction", "viscous_friction", "stribeck_friction", "pressure_dependent_friction", "leak",
         "heat_transfer", "valve_lag", "transport_delay", "hysteresis", "backlash", "nonlinear_stiffness",
         "saturation", "sensor_offset", "sensor_gain", "constant_load", "coulomb_viscous_friction",
         "modulated_friction")

_FAMILIES = {**{k: (build_friction, explain_friction) for k in FRICTION_KINDS},
             **{k: (build_load, explain_load) for k in LOAD_KINDS},
             **{k: (build_modulated, explain_modulated) for k in MODULATED_KINDS},
             **{k: (build_storage, explain_storage) for k in STORAGE_KINDS},
             **{k: (build_signal, explain_signal) for k in INPUT_KINDS + OUTPUT_KINDS}}   # saturation: both
assert set(_FAMILIES) == set(KINDS)


def _family(cand):
    """(build, explain) of a candidate: by kind, and for ``saturation`` by place (a junction's
    storage content, an input, an output)."""
    if cand.kind == "saturation" and cand.place.kind == "junction":
        return build_storage, explain_storage
    return _FAMILIES[cand.kind]


@dataclass(frozen=True)
class Candidate:
    """One kind of missing physics at one place.

    Parameters
    ----------
    kind : str
        One of :data:`KINDS`.
    place : Place
        Where it is attached.
    params : list of ParamSpec
        Fitted parameters (graph parameter names, guesses, bounds, units).
    regime : str, optional
        The regime variable the law depends on (the pressure of
        ``pressure_dependent_friction``), as an expression of the model.
    constants : tuple of (name, value, unit, description)
        Fixed graph parameters the law uses (smoothing flow, reference and
        ambient pressures).
    target : str, optional
        The element acted on (the C of ``nonlinear_stiffness`` / ``backlash``).
    initial : dict str -> float
        Initial values of the states the candidate adds.
    starts : tuple of dict
        Alternative starting values (by parameter name, within the bounds) the fit
        compares with the guess before it descends: effects such as a saturation
        are invisible from a start where they never act.
    """

    kind: str
    place: Place
    params: list
    regime: str | None = None
    constants: tuple = ()
    target: str | None = None
    initial: dict = field(default_factory=dict)
    starts: tuple = ()

    def __post_init__(self):
        if self.kind not in KINDS:
            raise DiagnosisError(f"unknown kind {self.kind!r}; expected one of {', '.join(KINDS)}")
        if not isinstance(self.place, Place):
            raise DiagnosisError(f"candidate {self.kind}: place must be a Place, got {self.place!r}")
        specs = {p.name: p for p in self.params}
        for start in self.starts:
            for name, value in start.items():
                if name not in specs or not specs[name].lower <= value <= specs[name].upper:
                    raise DiagnosisError(f"candidate {self.kind}: start {start} is not within the bounds of "
                                         f"its parameters {list(specs)}")

    @property
    def n_params(self) -> int:
        """Number of fitted parameters."""
        return len(self.params)

    def guesses(self) -> dict[str, float]:
        """Starting values by parameter name."""
        return {p.name: p.guess for p in self.params}

    def values_with_guesses(self, values=None) -> dict[str, float]:
        """`values` completed with the guesses; unknown names raise UnknownNameError."""
        values = dict(values or {})
        known = self.guesses()
        unknown = sorted(set(values) - set(known))
        if unknown:
            raise UnknownNameError("parameter", unknown[0], known, model=f"candidate {self}")
        known.update({k: float(v) for k, v in values.items()})
        return known

    def settle(self, values: dict, experiment) -> dict:
        """Fitted `values` with what the training data cannot tell released.

        A saturation limit that no training sample of the input goes beyond has no
        evidence behind it: it is moved to its outer bound (no limit on that side).
        Other kinds are returned unchanged.
        """
        values = dict(values)
        if (self.kind == "saturation" and self.place.kind == "input" and experiment is not None
                and self.place.name in experiment.inputs):
            u = np.asarray(experiment.inputs[self.place.name], dtype=float)
            low, high = self.params
            if not np.any(u < values[low.name]):
                values[low.name] = low.lower
            if not np.any(u > values[high.name]):
                values[high.name] = high.upper
        return values

    def build(self, model_graph, values=None):
        """A new graph: `model_graph` with this effect added.

        Parameters
        ----------
        model_graph : BondGraph
            The nominal graph (not modified).
        values : dict str -> float, optional
            Parameter values by :attr:`ParamSpec.name` (SI); missing ones take their guess.

        Returns
        -------
        BondGraph
            Named ``<model>_<kind>``; the fitted parameters and constants are graph parameters.
        """
        values = self.values_with_guesses(values)
        data = model_graph.to_dict()
        data["name"] = f"{model_graph.name}_{self.kind}"
        data["description"] = f"{model_graph.description} + {self.kind} at {self.place}".strip(" +")
        for spec in self.params:
            add_parameter(data, spec.name, values[spec.name], spec.unit, spec.description)
        for name, value, unit, description in self.constants:
            add_parameter(data, name, value, unit, description)
        build, _ = _family(self)
        build(data, model_graph, self, values)
        return graph_from_dict(data, source=f"candidate {self.kind} at {self.place}")

    def explain(self, values=None) -> str:
        """The effect in plain language, with the values and their units."""
        values = self.values_with_guesses(values)
        units = {p.name: p.unit for p in self.params}

        def show(name):
            unit = units.get(name, "")
            return f"{values[name]:.3g} {unit if unit != '1' else ''}".strip()

        _, explain = _family(self)
        return explain(self, values, show)

    def __str__(self) -> str:
        return f"{self.kind} at {self.place}"


def candidates(graph, place: Place, *, regime_variables=None, experiment=None) -> list[Candidate]:
    """The kinds that make physical sense at `place`, with guesses scaled from the data.

    Parameters
    ----------
    graph : BondGraph
        The nominal model.
    place : Place
        A junction (kind ``"1"`` or ``"0"``), an input or an output of `graph`.
    regime_variables : dict, optional
        From :func:`diagnosis.locate.regime_variables` (name -> (values, description)); a
        pressure-dependent friction is offered for each pressure variable of the model,
        first those whose name appears here.
    experiment : Experiment, optional
        Recorded inputs/outputs (model units); scales for guesses and bounds come from
        a nominal simulation on it.  Without it every scale is 1 (SI).

    Returns
    -------
    list of Candidate
        In the order of :data:`KINDS`.

    Examples
    --------
    >>> from plants import library
    >>> msd = library.build("mass-spring-damper")
    >>> [c.kind for c in candidates(msd, Place("output", "x"))]
    ['saturation', 'sensor_offset', 'sensor_gain']
    >>> offset = candidates(msd, Place("output", "x"))[1]
    >>> offset.build(msd, {"offset_x": 0.01}).equations().h[0]
    offset_x + q_k
    >>> offset.explain({"offset_x": 0.01})
    'the x sensor reads 0.01 m off: a sensor offset on output x'
    """
    if not isinstance(place, Place):
        raise DiagnosisError(f"place must be a diagnosis.place.Place, got {place!r}")
    taken = set(graph.names())
    if place.kind == "junction":
        element = graph.elements.get(place.name)
        if element is None or element.kind not in ("0", "1"):
            junctions = [n for n, e in graph.elements.items() if e.kind in ("0", "1")]
            raise UnknownNameError("junction", place.name, junctions, model=graph.name)
        signals = modulating_signals(graph, place.name, regime_variables) if element.kind == "1" else {}
        scales, values = junction_scales(graph, place.name, experiment, signals)
        protos = make_storage(graph, place, scales, taken, values) + make_load(graph, place, scales, taken)
        if element.kind == "1":
            friction = make_friction(graph, place, scales, taken, values)
            v_eps = next(p["constants"][0] for p in friction if p["kind"] == "coulomb_friction")
            protos = friction + make_modulated(graph, place, scales, taken, values, v_eps) + protos
            protos = _regime_first(protos, regime_variables)
    elif place.kind == "input":
        names = [d.name for d in graph.inputs()]
        if place.name not in names:
            raise UnknownNameError("input", place.name, names, model=graph.name)
        span, dt = experiment_times(experiment) if experiment is not None else (1.0, 0.01)
        recorded = experiment.inputs.get(place.name) if experiment is not None else None
        protos = make_input(graph, place, span, dt, recorded, taken)
    else:
        if place.name not in graph.outputs:
            raise UnknownNameError("output", place.name, list(graph.outputs), model=graph.name)
        measured = experiment.outputs.get(place.name) if experiment is not None else None
        protos = make_output(graph, place, None if measured is None else np.asarray(measured, float), taken)
    out = [Candidate(p["kind"], place, list(p["params"]), regime=p.get("regime"),
                     constants=tuple(p.get("constants", ())), target=p.get("target"),
                     initial=dict(p.get("initial", {})), starts=tuple(p.get("starts", ()))) for p in protos]
    return sorted(out, key=lambda c: KINDS.index(c.kind))


def _regime_first(protos: list[dict], regime_variables) -> list[dict]:
    """Pressure-dependent frictions whose pressure is among the located regime variables first."""
    if not regime_variables:
        return protos
    named = set(regime_variables)
    return sorted(protos, key=lambda p: p.get("regime") is not None and p["regime"] not in named)
