"""What every kind of missing physics is: a :class:`Kind`, registered under its name.

A kind says where it may attach (:attr:`Kind.doors`: ``"1"`` or ``"0"`` for a 1- or 0-junction,
``"input"``, ``"output"``), proposes its parameters at one place (:meth:`Kind.propose`, from a
:class:`Site`: the model, the place and the scales read off the data), builds the model with the
effect through the graph-editing API of :mod:`bondgraph.editing` (:meth:`Kind.build`) and says
what a fit found in words (:meth:`Kind.explain`); :meth:`Kind.settle` may release what the
training data cannot tell.  :meth:`Kind.features` is the hook for the
feature regression (what a kind's effect looks like in the residual); it answers None here.

:func:`register` adds a kind to :data:`REGISTRY` (by name, in registration order: the catalogue
order, :data:`diagnosis.catalogue.KINDS`).  :mod:`diagnosis.kinds` imports one module per kind.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from itertools import permutations
from typing import ClassVar

import numpy as np

from ..catalogue_common import ParamSpec
from ..catalogue_scales import Scales
from ..errors import DiagnosisError
from ..place import Place

__all__ = ["Kind", "Site", "Proposal", "DOORS", "REGISTRY", "register", "kind_named", "hang", "extends", "holds"]

#: The places a kind may attach to: a 1-junction, a 0-junction, a recorded input, a measured output.
DOORS = ("1", "0", "input", "output")


@dataclass(frozen=True)
class Site:
    """What a kind sees of its place when it proposes parameters.

    Attributes
    ----------
    graph : BondGraph
        The nominal model.
    place : Place
        Where the candidate attaches.
    door : str
        One of :data:`DOORS`: the junction's type, or the place's kind.
    taken : frozenset of str
        Names the model already uses (new names are made fresh against them).
    scales : Scales
        Typical magnitudes at a junction (:func:`~diagnosis.catalogue_scales.junction_scales`);
        unit scales and the experiment's span and step elsewhere.
    values : dict
        Nominal values at a junction (``e_<bond>``, ``state:<name>``, ``pressure:<label>``,
        ``signal:<label>``), from the nominal simulation; empty without data.
    regime_variables : dict or None
        Located regime variables (:func:`diagnosis.locate.regime_variables`).
    signals : dict
        Signals that may modulate a friction at a 1-junction (label -> expression).
    recorded : ndarray or None
        The recorded input (input sites) or the measured output (output sites), model units.
    x0 : dict or None
        The state the recording starts from (state name -> value; None: the model's own).
    """

    graph: object
    place: Place
    door: str
    taken: frozenset
    scales: Scales = Scales()
    values: dict = field(default_factory=dict)
    regime_variables: dict | None = None
    signals: dict = field(default_factory=dict)
    recorded: object = None
    x0: dict | None = None

    @property
    def name(self) -> str:
        """The place's name (junction, input or output)."""
        return self.place.name

    @property
    def effort(self):
        """The effort of the junction's first bond along the nominal run (a 0-junction's common
        effort: its pressure, its temperature), or None without data."""
        return self.values.get(f"e_{self.graph.bonds_of(self.name)[0][0].name}")

    @cached_property
    def shared(self) -> dict:
        """Values the kinds at this site compute once and share (e.g. an input's resting value)."""
        return {}


@dataclass(frozen=True)
class Proposal:
    """One candidate a kind proposes at a site: its fitted parameters and what else it needs
    (the fields of :class:`~diagnosis.catalogue.Candidate` but kind and place)."""

    params: tuple
    constants: tuple = ()
    regime: str | None = None
    target: str | None = None
    initial: dict = field(default_factory=dict)
    starts: tuple = ()

    def __post_init__(self):
        if not all(isinstance(p, ParamSpec) for p in self.params):
            raise DiagnosisError(f"a proposal's params must be ParamSpec objects, got {self.params!r}")


class Kind:
    """One kind of missing physics.  Subclass, set :attr:`name` and :attr:`doors`, write
    :meth:`propose`, :meth:`build` and :meth:`explain`, and decorate with :func:`register`."""

    #: the kind's name, one word of the catalogue's vocabulary
    name: ClassVar[str] = ""
    #: where it may attach: some of :data:`DOORS`
    doors: ClassVar[tuple] = ()
    #: the energy domains whose junctions its physics lives at (None: any), e.g. a dry friction's
    #: mechanical ones; a junction of the ``"generic"`` domain admits every kind (:meth:`admits`)
    domains: ClassVar[tuple | None] = None
    #: the junction kinds (``"1"``, ``"0"``) at which :meth:`features` applies ("" none)
    feature_doors: ClassVar[str] = ""
    #: the feature columns in words (the documentation's table)
    feature_names: ClassVar[tuple] = ()
    #: the parameters its feature group is priced by (the candidate's; a grid choice such as a
    #: Stribeck velocity counting as one)
    feature_price: ClassVar[int] = 0
    #: how many leading parameters the feature coefficients estimate directly, in
    #: :attr:`feature_names` order (a level from ``sign(v)``, a coefficient from ``v``): each
    #: candidate's fit also starts there (:func:`diagnosis.features.with_feature_starts`)
    feature_params: ClassVar[int] = 0
    #: the law's sign of the leading feature coefficients, in :attr:`feature_names` order: +1 where
    #: the coefficient (the catalogue's sign: what the element takes) cannot be negative, a friction
    #: level, a damping, a leak's conductance: energy taken, never given (0: either sign).  The
    #: feature regression keeps no selection that breaks it (:func:`diagnosis.features.regress_kinds`)
    feature_signs: ClassVar[tuple] = ()
    #: the parameters (indices) a feature group's grid value sets, in the order of
    #: ``FeatureGroup.grid`` (a Stribeck velocity, a modulating signal's lag)
    feature_grid_params: ClassVar[tuple] = ()
    #: the simpler kinds this one extends: simpler kind -> {own parameter index: the simpler's
    #: parameter index}; the other parameters at 0 reduce this law to the simpler one
    #: (:meth:`start_from`)
    nests: ClassVar[dict] = {}
    #: whether :meth:`build` rewrites the law of the candidate's target element (a storage kind's
    #: cubic term, dead band or end stop); a kind that only refits the target's own value does not,
    #: and so combines with one that does (:func:`diagnosis.pairs.targets`)
    rewrites_target: ClassVar[bool] = True
    #: an output kind fitted also at the outputs graph location did not rank
    #: (:func:`diagnosis.place_choice.sensor_places`): a sensor's static error (an offset, a gain, a
    #: range) shows on its own output only, where a larger residual elsewhere hides it; a sensor's
    #: dynamics (a lag) is located like any place (graph location's output correction lags too) and
    #: trades against every dynamic effect on that output, so it is fitted where it is ranked
    unranked_sensor: ClassVar[bool] = True
    #: fitted only where its features are significant and rank among the best at the place
    #: (:func:`diagnosis.features.prune_candidates`): a law flexible enough to stand in for others
    #: (a load periodic in the travel for a mass's error along a travel one way)
    needs_evidence: ClassVar[bool] = False

    def admits(self, door: str, domain: str) -> bool:
        """Whether this kind may attach at a place of `door` whose junction is of `domain`: the door
        is one of :attr:`doors` and, at a junction, the domain one of :attr:`domains` (or
        ``"generic"``: a model that names no domain is not second-guessed).  A Coulomb friction at
        the heat-flow junction of a thermal model is no physics (a heater block's radiation loss
        had been answered by the friction kinds' features)."""
        if door not in self.doors:
            return False
        return door not in ("1", "0") or self.domains is None or domain in self.domains + ("generic",)

    def propose(self, site: Site) -> list[Proposal]:
        """The candidates of this kind at `site` (none where the domain does not fit)."""
        raise NotImplementedError

    def build(self, graph, cand, values: dict):
        """`graph` with the effect of `cand` at its place, through the editing API (a new graph).

        `values` holds every fitted parameter's value; the candidate's parameters and constants
        are declared on the result by :meth:`Candidate.build <diagnosis.catalogue.Candidate.build>`,
        so the new elements simply use their names.
        """
        raise NotImplementedError

    def explain(self, cand, values: dict, show) -> str:
        """The effect in plain language (`show(name)` formats a value with its unit)."""
        raise NotImplementedError

    def settle(self, cand, values: dict, experiment) -> dict:
        """Fitted `values` with what the training data cannot tell released (unchanged here)."""
        return values

    def unexcited(self, junction: str, values: dict) -> str:
        """Why the recording never excites what sets this kind apart from a simpler kind it nests
        (:attr:`nests`), at `junction` (the nominal values there,
        :func:`~diagnosis.catalogue_scales.junction_scales`), in words; "" when it does (here
        always).  A kind that is not proposed on such a recording names the reason, and the report
        lists it beside the simpler answer as a reading not told apart
        (:func:`diagnosis.alternatives.unexcited`)."""
        return ""

    def start_from(self, cand, simpler, values: dict) -> dict | None:
        """A start for `cand` where a fit of the `simpler` candidate it extends (same place, a
        kind in :attr:`nests`) ended with `values`: the mapped parameters take the simpler fit's
        values, the others 0 (the simpler law) where the bounds allow, else their guess; None
        when this kind does not extend that one.  A richer law then starts no worse than the
        simpler one fitted, instead of from a guess a hopeless-fit rule may give up on."""
        mapping = self.nests.get(simpler.kind)
        if mapping is None:
            return None
        start = {}
        for i, spec in enumerate(cand.params):
            if i in mapping:
                value = values.get(simpler.params[mapping[i]].name, spec.guess)
            else:
                value = 0.0 if spec.lower <= 0.0 <= spec.upper else spec.guess
            start[spec.name] = spec.clipped(value)
        return start

    def starts_from(self, cand, simpler, values: dict) -> list:
        """The starts for `cand` where a fit of the `simpler` candidate it extends ended with
        `values`: :meth:`start_from`'s (none when this kind does not extend that one).  A kind
        whose extra terms are invisible at 0 adds more."""
        start = self.start_from(cand, simpler, values)
        return [] if start is None else [start]

    def reduced_start(self, cand, simpler, values: dict) -> dict | None:
        """A start for the `simpler` candidate (a kind in :attr:`nests`, same place) where a fit of
        `cand` ended with `values`: the mapped parameters at that fit's values, the others at their
        guess; None when this kind does not extend that one.  The inverse of :meth:`start_from`:
        a richer fit that went further along the shared parameters (a sign's smoothing) with its
        extra terms near 0 is then matched by the simpler law, which the choice prices lower."""
        mapping = self.nests.get(simpler.kind)
        if mapping is None:
            return None
        return {simpler.params[j].name: simpler.params[j].clipped(values.get(cand.params[i].name,
                                                                             simpler.params[j].guess))
                for i, j in mapping.items()}

    def combined_starts(self, cand, tried: list) -> list:
        """Further starts for `cand` once its own were tried: `tried` lists ``(start, cost)``
        (start: parameter name -> value, cost: its training cost).  None here; a kind whose
        parameters act apart (a range's two limits) combines the best of each."""
        return []

    def feature_start(self, cand, evidence) -> dict | None:
        """A start for `cand` from the feature regression of its kind at its place (`evidence`, a
        :class:`~diagnosis.features.KindEvidence`): its :attr:`feature_params` leading parameters
        at their feature coefficients, and its :attr:`feature_grid_params` at the grid value the
        regression chose (:attr:`KindEvidence.grid <diagnosis.features.KindEvidence>`), clipped
        to their bounds; None without such coefficients.  A kind whose grid sets its parameters
        otherwise (an end stop's position on one side or both) overrides it."""
        n = self.feature_params
        coef = [evidence.coefficients.get(name) for name in self.feature_names[:n]] if n else []
        if not coef or not all(c is not None and np.isfinite(c) for c in coef):
            return None
        start = {spec.name: spec.clipped(c) for spec, c in zip(cand.params, coef)}
        if self.feature_grid_params and len(evidence.grid) == len(self.feature_grid_params):
            for i, value in zip(self.feature_grid_params, evidence.grid):
                start[cand.params[i].name] = cand.params[i].clipped(value)
        return start

    def features(self, signals) -> list:
        """What this kind's effect looks like at a junction, for the feature regression
        (:mod:`diagnosis.features`): its :class:`~diagnosis.kinds.feature_signals.FeatureGroup`
        s from the junction's :class:`~diagnosis.kinds.feature_signals.FeatureSignals`, one per
        variant (none here: the kind declares no features)."""
        return []

    def __repr__(self) -> str:
        return f"<kind {self.name} at {', '.join(self.doors)}>"


#: name -> Kind instance, in the catalogue order
REGISTRY: dict[str, Kind] = {}


def register(cls):
    """Class decorator: add an instance of the :class:`Kind` subclass `cls` to :data:`REGISTRY`."""
    if not (isinstance(cls, type) and issubclass(cls, Kind)) or not cls.name.isidentifier():
        raise DiagnosisError(f"register() takes a Kind subclass with a name, got {cls!r}")
    if cls.name in REGISTRY:
        raise DiagnosisError(f"kind {cls.name!r} is registered twice")
    bad = [d for d in cls.doors if d not in DOORS]
    if not cls.doors or bad:
        raise DiagnosisError(f"kind {cls.name!r}: doors must be some of {DOORS}, got {cls.doors!r}")
    REGISTRY[cls.name] = cls()
    return cls


def kind_named(name: str) -> Kind:
    """The registered kind called `name`."""
    if name not in REGISTRY:
        raise DiagnosisError(f"unknown kind {name!r}; expected one of {', '.join(REGISTRY)}")
    return REGISTRY[name]


def hang(graph, element, junction: str):
    """`graph` with `element` bonded to `junction` by a bond ``b_<element>``."""
    return graph.insert(element, at=junction, bond=f"b_{element.name}")


def extends(richer, simpler) -> bool:
    """Whether candidate `richer` extends candidate `simpler`: a kind it nests
    (:attr:`Kind.nests`), at the same place and regime, so that its extra parameters at 0 are
    `simpler`'s law.  A group of twins extends nothing and is extended by nothing."""
    return (richer is not None and simpler is not None and hasattr(richer, "definition")
            and not hasattr(simpler, "members") and richer.place == simpler.place
            and richer.kind != simpler.kind and simpler.kind in richer.definition.nests
            and getattr(simpler, "regime", None) in (None, getattr(richer, "regime", None)))


def holds(richer, simpler) -> bool:
    """Whether model `richer` holds `simpler`: each member of `simpler` (a candidate, or a pair or
    group of candidates, each member with parameters of its own) is one of `richer`'s (same kind,
    place, regime and element) or extended by one (:func:`extends`), each matched once, and
    `richer` adds something (a member more, or an extension).  At its extra parameters' neutral
    values (a friction's extra terms at 0, a value refitted at the nominal) `richer` is then
    `simpler`: a Stribeck friction beside an inertia refitted holds a Coulomb friction beside it,
    and a Coulomb friction alone.

    Examples
    --------
    >>> from types import SimpleNamespace as NS
    >>> coulomb, value = NS(kind="coulomb_friction", place="w"), NS(kind="nominal_value", place="w")
    >>> pair = NS(members=(coulomb, value))
    >>> holds(pair, coulomb), holds(coulomb, pair), holds(pair, pair)
    (True, False, False)
    """
    if richer is None or simpler is None:
        return False
    big, small = list(getattr(richer, "members", (richer,))), list(getattr(simpler, "members", (simpler,)))
    if len(small) > len(big):
        return False
    for matched in permutations(big, len(small)):
        same = [_key(r) == _key(s) for r, s in zip(matched, small)]
        if all(a or extends(r, s) for a, r, s in zip(same, matched, small)):
            return len(big) > len(small) or not all(same)
    return False


def _key(candidate) -> tuple:
    return (candidate.kind, str(getattr(candidate, "place", None)), getattr(candidate, "regime", None),
            getattr(candidate, "target", None))
