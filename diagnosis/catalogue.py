"""The catalogue of candidate physics: what a model may be missing, by physical name.

Each :class:`Candidate` is one kind of effect (:data:`KINDS`) attached to one
:class:`~diagnosis.place.Place`, with fitted parameters (:class:`ParamSpec`:
guess and bounds scaled from the data) and fixed constants.
:meth:`Candidate.build` returns a NEW graph with the effect added as a proper
bond-graph element (R with a nonlinear law, C with a changed law, equation
element, 1-junction branch), an input transformation (the element reading the
input gets the lag / delay / saturation, with its extra states) or an output
transformation, made through the graph-editing API of :mod:`bondgraph.editing`.
Candidate parameters are graph parameters, so a compiled candidate is re-run
with new values, and the graph saves to JSON and exports to an FMU like any other.

The kinds themselves are classes in a registry, one module each, in :mod:`diagnosis.kinds`:
a :class:`~diagnosis.kinds.base.Kind` says where it may attach (its doors), proposes its
parameters at a place, builds and explains.  This module turns their proposals into
candidates.  Which kinds at which place (:func:`candidates`):

* 1-junction: ``coulomb_friction``, ``viscous_friction``, ``coulomb_viscous_friction``,
  ``asymmetric_viscous_friction``, ``quadratic_drag``,
  ``stribeck_friction``, ``pressure_dependent_friction`` (one per pressure variable
  of the model), ``modulated_friction`` (one per input and per listed effort of
  another domain, :func:`~diagnosis.kinds.modulated_friction.modulating_signals`),
  ``hysteresis``, and for each C on it ``backlash``, ``nonlinear_stiffness``
  (with the C's own linear value refitted), ``saturation`` (end stops);
* 0-junction: ``leak``, ``heat_transfer`` (pneumatic / thermal only),
  ``nonlinear_stiffness`` and ``saturation`` (an overflow) for each C on it;
* 0- and 1-junction: ``constant_load``, and ``nominal_value`` for each linear I, C or R on it
  (its own value refitted alone: no physics missing, the nominal's value off; an R's only down
  at a 1-junction and up at a 0-junction);
* input: ``valve_lag``, ``transport_delay``, ``saturation``;
* output: ``saturation`` (the sensor's range), ``sensor_offset``, ``sensor_gain``;
* law (a constitutive law whose bond ends at no junction, :mod:`diagnosis.law_places`: a
  muscle's force law): the kinds of the junction that splits its bond, a 1-junction for a law
  that sets the effort (friction, hysteresis, a constant load in series with the law), a
  0-junction for one that sets the flow.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from bondgraph import Param

from .catalogue_common import ParamSpec, junction_domain, priced
from .catalogue_scales import Scales, command_hold, experiment_times, junction_scales
from .errors import DiagnosisError, UnknownNameError
from .kinds import KINDS, REGISTRY, Site, kind_named
from .kinds.modulated_friction import modulating_signals
from .place import Place

__all__ = ["KINDS", "ParamSpec", "Candidate", "candidates", "site_of"]


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
        if self.kind not in REGISTRY:
            raise DiagnosisError(f"unknown kind {self.kind!r}; expected one of {', '.join(REGISTRY)}")
        if not isinstance(self.place, Place):
            raise DiagnosisError(f"candidate {self.kind}: place must be a Place, got {self.place!r}")
        specs = {p.name: p for p in self.params}
        for start in self.starts:
            for name, value in start.items():
                if name not in specs or not specs[name].lower <= value <= specs[name].upper:
                    raise DiagnosisError(f"candidate {self.kind}: start {start} is not within the bounds of "
                                         f"its parameters {list(specs)}")

    @property
    def definition(self):
        """The registered :class:`~diagnosis.kinds.base.Kind` of this candidate (its doors,
        builder, explanation and features hook)."""
        return kind_named(self.kind)

    @property
    def n_params(self) -> int:
        """Number of fitted parameters the choice prices (:attr:`ParamSpec.priced`)."""
        return priced(self.params)

    def guesses(self) -> dict[str, float]:
        """Starting values by parameter name."""
        return {p.name: p.guess for p in self.params}

    def within_bounds(self, values) -> dict[str, float]:
        """`values` of this candidate's own parameters (others left out), each clipped into its
        bounds: where a fit ended, as a start (a saturation limit the data gave no evidence for
        was released beyond its bound)."""
        return {p.name: float(min(max(float(values[p.name]), p.lower), p.upper)) for p in self.params
                if p.name in values}

    def with_starts(self, starts) -> "Candidate":
        """This candidate with the fit starts `starts` (dicts name -> value) after its own; itself
        when there are none."""
        starts = tuple(starts)
        return replace(self, starts=tuple(self.starts) + starts) if starts else self

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
        return self.definition.settle(self, dict(values), experiment)

    def combined_starts(self, tried: list) -> list:
        """Starts to try after :attr:`starts` (see :meth:`Kind.combined_starts
        <diagnosis.kinds.base.Kind.combined_starts>`); `tried` lists ``(start, training cost)``."""
        return self.definition.combined_starts(self, tried)

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
        graph = model_graph.copy(name=f"{model_graph.name}_{self.kind}",
                                 description=f"{model_graph.description} + {self.kind} at {self.place}".strip(" +"))
        from .law_places import at_junction
        graph, at = at_junction(graph, self.place)      # a law's bond split by a junction
        graph = self.definition.build(graph, self if at == self.place else replace(self, place=at), values)
        known = graph.parameters()      # a parameter the model has already (a C's own value) is refitted
        declared = [Param(spec.name, values[spec.name], spec.unit, spec.description)
                    for spec in self.params if spec.name not in known]
        declared += [Param(name, value, unit, description) for name, value, unit, description in self.constants]
        refitted = {spec.name: values[spec.name] for spec in self.params if spec.name in known}
        return graph.declare(*declared).with_params(refitted)

    def explain(self, values=None) -> str:
        """The effect in plain language, with the values and their units."""
        values = self.values_with_guesses(values)
        units = {p.name: p.unit for p in self.params}

        def show(name):
            unit = units.get(name, "")
            return f"{values[name]:.3g} {unit if unit != '1' else ''}".strip()

        return self.definition.explain(self, values, show)

    def __str__(self) -> str:
        return f"{self.kind} at {self.place}"


def candidates(graph, place: Place, *, regime_variables=None, experiment=None, x0=None,
               kinds=None, estimate=None) -> list[Candidate]:
    """The kinds that make physical sense at `place`, with guesses scaled from the data.

    Parameters
    ----------
    graph : BondGraph
        The nominal model.
    place : Place
        A junction (kind ``"1"`` or ``"0"``), an input, an output or a law place of `graph`
        (:mod:`diagnosis.law_places`: the junction kinds at the junction that splits its bond).
    regime_variables : dict, optional
        From :func:`diagnosis.locate.regime_variables` (name -> (values, description)); a
        pressure-dependent friction is offered for each pressure variable of the model,
        first those whose name appears here.
    experiment : Experiment, optional
        Recorded inputs/outputs (model units); scales for guesses and bounds come from
        a nominal simulation on it.  Without it every scale is 1 (SI).
    x0 : dict or array, optional
        The state that simulation starts from (the recording's; default the model's).
    kinds : iterable of str, optional
        Only these kinds are proposed (default: every kind; proposing one may simulate, as an
        input's kinds read where it rests).
    estimate : ndarray, optional
        At a junction, the located correction there on `experiment`'s times
        (:attr:`diagnosis.graph_location.PlaceScore.estimate`): the values are read along the
        run it corrects (:func:`~diagnosis.catalogue_scales.junction_scales`), for a nominal
        whose own run drifts away from the recording.

    Returns
    -------
    list of Candidate
        In the order of :data:`KINDS`; at a 1-junction, within a kind, those whose regime
        expression is among `regime_variables` first.

    Examples
    --------
    >>> from plants import library
    >>> msd = library.build("mass-spring-damper")
    >>> [c.kind for c in candidates(msd, Place("output", "x"))]
    ['saturation', 'sensor_offset', 'sensor_gain', 'sensor_lag']
    >>> offset = candidates(msd, Place("output", "x"))[1]
    >>> offset.build(msd, {"offset_x": 0.01}).equations().h[0]
    offset_x + q_k
    >>> offset.explain({"offset_x": 0.01})
    'the x sensor reads 0.01 m off: a sensor offset on output x'
    """
    if place.kind == "law":
        # the junction kinds at the junction that splits the law's bond (diagnosis.law_places)
        from .law_places import at_junction
        split, at = at_junction(graph, place)
        return [replace(c, place=place) for c in candidates(split, at, regime_variables=regime_variables,
                                                            experiment=experiment, x0=x0, kinds=kinds)]
    site = site_of(graph, place, regime_variables=regime_variables, experiment=experiment, x0=x0,
                   estimate=estimate)
    domain = junction_domain(graph, place.name) if site.door in ("1", "0") else "generic"
    out = [Candidate(kind.name, place, list(prop.params), regime=prop.regime, constants=tuple(prop.constants),
                     target=prop.target, initial=dict(prop.initial), starts=tuple(prop.starts))
           for kind in REGISTRY.values() if (kinds is None or kind.name in kinds) and kind.admits(site.door, domain)
           for prop in kind.propose(site)]
    order = list(REGISTRY)
    named = set(regime_variables or ()) if site.door == "1" else None
    # at a 1-junction, within a kind, laws of a located regime variable first (a pressure, a signal)
    return sorted(out, key=lambda c: (order.index(c.kind), named is not None and bool(named)
                                      and c.regime is not None and c.regime not in named))


def site_of(graph, place: Place, *, regime_variables=None, experiment=None, x0=None, estimate=None) -> Site:
    """What the kinds see at `place` (:class:`~diagnosis.kinds.base.Site`): its door, the names
    taken, and the scales and nominal values read off a simulation of `experiment` from `x0`; a place the
    model does not have is an :class:`UnknownNameError` listing those it has."""
    if not isinstance(place, Place):
        raise DiagnosisError(f"place must be a diagnosis.place.Place, got {place!r}")
    taken = frozenset(graph.names())
    if place.kind == "junction":
        element = graph.elements.get(place.name)
        if element is None or element.kind not in ("0", "1"):
            junctions = [n for n, e in graph.elements.items() if e.kind in ("0", "1")]
            raise UnknownNameError("junction", place.name, junctions, model=graph.name)
        signals = modulating_signals(graph, place.name, regime_variables) if element.kind == "1" else {}
        scales, values = junction_scales(graph, place.name, experiment, signals, x0=x0, estimate=estimate)
        return Site(graph, place, element.kind, taken, scales, dict(values or {}), regime_variables, signals)
    span, dt = experiment_times(experiment) if experiment is not None else (1.0, 0.01)
    if place.kind == "input":
        names = [d.name for d in graph.inputs()]
        if place.name not in names:
            raise UnknownNameError("input", place.name, names, model=graph.name)
        recorded = experiment.inputs.get(place.name) if experiment is not None else None
    else:
        if place.name not in graph.outputs:
            raise UnknownNameError("output", place.name, list(graph.outputs), model=graph.name)
        measured = experiment.outputs.get(place.name) if experiment is not None else None
        recorded = None if measured is None else np.asarray(measured, float)
    start = dict(x0) if isinstance(x0, dict) else None
    if x0 is not None and start is None:       # a state vector in the model's order
        start = dict(zip(graph.equations().state_names, map(float, np.ravel(x0))))
    hold = command_hold(experiment) if experiment is not None and place.kind == "output" else None
    return Site(graph, place, place.kind, taken, Scales(span=span, dt=dt, from_data=experiment is not None, hold=hold),
                regime_variables=regime_variables, recorded=recorded, x0=start)
