"""Which places' candidates are fitted, from graph location's scores.

Graph location (:mod:`diagnosis.graph_location`) ranks every junction, input and output by the
share of the residual a correction there explains.  The candidates of the best few are fitted
(:func:`located_places`), with the places location cannot tell from them: further places that
explain as much, the inputs that drive a located junction directly (:func:`actuator_places`), and the
springs that carry a located 0-junction's effort, for the kinds acting on a storage element
(:func:`spring_places`, :func:`on_storage`).
A constitutive law acting on a located junction through a lever arm or a gear is that junction's
companion (:func:`without_companions`, :func:`companions`): the kinds that fit best at the junction
are fitted at the law too (:func:`companion_candidates`).
"""
from __future__ import annotations

from bondgraph.editing_inputs import expression_fields, mentions
from bondgraph.elements import SOURCE_KINDS, TWO_PORT_KINDS

from .catalogue_common import junction_elements
from .place import Place

__all__ = ["located_places", "further_places", "actuator_places", "sensor_places", "spring_places", "on_storage",
           "without_companions", "companions", "companion_candidates", "MIN_PLACE_SHARE", "PLACE_TIE",
           "COMPANION_KINDS"]

#: places whose correction explains less than this share of the residual get no candidates
MIN_PLACE_SHARE = 0.02


def actuator_places(graph, places, experiment) -> list:
    """The recorded inputs that drive a located junction directly, as input places not yet in
    `places`: a source named after the input, or an element bonded to the junction whose law
    reads it (a valve's command), or a source that sets the common variable of a neighbouring
    junction (a flow source on a 1-junction bonded to a located 0-junction sets the flow of their
    bond: a human's imposed joint speed behind a located torque node).  An actuator's lag, delay or
    limit there changes the junction's flow or effort exactly as a correction at the junction does,
    so graph location cannot rank the input above the junction: its candidates are fitted with the
    junction's."""
    recorded = [d.name for d in graph.inputs() if d.name in experiment.inputs]
    have = {(p.kind, p.name) for p in places}
    out = []
    for p in places:
        if p.kind != "junction":
            continue
        for element in _driving_elements(graph, p.name):
            entry = element.to_dict()
            for u in recorded:
                reads = element.name == u or any(mentions(c[k], u) for c, k in expression_fields(entry))
                if reads and ("input", u) not in have:
                    have.add(("input", u))
                    out.append(Place("input", u))
    return out


def sensor_places(places, experiment) -> list:
    """The measured outputs not yet in `places`, as output places.  A sensor's error (a gain, an
    offset, a range) leaves a residual on its own output only, and behind a larger one an earlier
    round left on every output (a leak answered at the wrong tank) its share of the whole stays
    small: seed 3434's compound case 013 located a level sensor's 4 % gain error at 1.7 %, last of
    seven places.  Its candidates are few and cheap (no state of their own), so a further round
    fits them at every output where it located something (:func:`diagnosis.diagnose._further_round`)."""
    have = {(p.kind, p.name) for p in places}
    return [Place("output", o) for o in experiment.outputs if ("output", o) not in have]


def spring_places(graph, places) -> list:
    """The 1-junctions holding a C element and bonded to a located 0-junction, as junction places
    not yet in `places`.  A spring in series carries the 0-junction's effort (the torque node
    between two springs of a drive train): a change of its law (a hardening, a play, an end stop)
    shows there as a flow correction, and graph location ranks the 0-junctions of a chain of series
    springs alike, above the springs' own 1-junctions.  Only the kinds that act on the C
    (:func:`on_storage`) are fitted at these places: seed 3535's exoskeleton, whose interface spring
    k_eh hardened, located its three torque nodes and the gear spring's junction alike, and the
    nonlinear stiffness of k_eh was never fitted (case 036)."""
    have = {(p.kind, p.name) for p in places}
    out = []
    for p in places:
        if p.kind != "junction" or graph.elements[p.name].kind != "0":
            continue
        for element, _ in junction_elements(graph, p.name):
            if (element.kind == "1" and ("junction", element.name) not in have
                    and any(e.kind == "C" for e, _ in junction_elements(graph, element.name))):
                have.add(("junction", element.name))
                out.append(Place("junction", element.name))
    return out


def on_storage(graph, candidate) -> bool:
    """Whether `candidate` changes a C element's law or content (its target is a C)."""
    target = getattr(candidate, "target", None)
    return target is not None and target in graph.elements and graph.elements[target].kind == "C"


#: the source kinds that set a junction's common variable: the flow of a 1-, the effort of a 0-junction
_SETS_COMMON = {"1": ("Sf", "MSf"), "0": ("Se", "MSe")}


def _driving_elements(graph, junction: str) -> list:
    """The elements bonded to `junction`, and the sources that set what one of its bonds carries:
    a source on a neighbouring junction setting the neighbour's common variable
    (:data:`_SETS_COMMON`), and, behind a transformer or gyrator bonded to `junction`, the source on
    its other port or the source setting the common variable of the junction there (a chamber
    pressure behind a piston's area: an error of the pressure is a force at the piston, scaled)."""
    out = []
    for element, _ in junction_elements(graph, junction):
        out.append(element)
        beyond = [element]
        if element.kind in TWO_PORT_KINDS:
            beyond = [e for e, _ in junction_elements(graph, element.name) if e.name != junction]
            out += [e for e in beyond if e.kind in SOURCE_KINDS]
        for e in beyond:
            if e.ports is None:                            # a neighbouring junction
                out += [s for s, _ in junction_elements(graph, e.name) if s.kind in _SETS_COMMON.get(e.kind, ())]
    return out


#: Places the location cannot tell from the ``top``-th: what they leave unexplained is within
#: this factor of what it leaves.
PLACE_TIE = 1.10


def located_places(scores, top: int) -> list:
    """The place scores whose candidates are fitted: the ``top`` best, and, when the ``top``-th
    explains most of the residual (half or more), every further place the location cannot tell
    from it (the share of the residual it leaves is within :data:`PLACE_TIE` of that place's:
    a series spring's 1-junction and the 0-junctions of the torque it carries explain the
    same), at most ``2 top``; none explaining under :data:`MIN_PLACE_SHARE`.  (Where the
    location explains little, it separates little: more places would only crowd the fits.)"""
    kept = [s for s in scores if s.explained >= MIN_PLACE_SHARE]
    if len(kept) <= top or top < 1 or kept[top - 1].explained < 0.5:
        return kept[:max(top, 0)]
    last = 1.0 - kept[top - 1].explained
    tied = [s for s in kept[top:2 * top] if 1.0 - s.explained <= PLACE_TIE * last]
    return kept[:top] + tied


def further_places(graph, scores, top: int, experiment) -> tuple[list, list, list]:
    """``(places, springs, sensors)``: the place scores a further round fits its candidates at (the
    located ones, :func:`located_places`; the actuators that drive them; the sensors behind them
    when something was located; the series springs of located 0-junctions), which of them are
    springs (storage kinds only) and which sensors added unranked (their
    :attr:`~diagnosis.kinds.base.Kind.unranked_sensor` kinds only).  The added places are looked
    up among `scores` by kind and name: graph location names a junction with the bond it reports
    it by, which the added places lack, and the springs were lost so in every further round (seed
    6767, compound case 005: the exoskeleton's hardening k_s was never fitted in round 2, and the
    gear spring k_g answered)."""
    places = located_places(without_companions(graph, scores), top)
    by_name = {(s.place.kind, s.place.name): s for s in scores}

    def scored(added):
        return [by_name[(p.kind, p.name)] for p in added if (p.kind, p.name) in by_name]

    places += scored(actuator_places(graph, [s.place for s in places], experiment))
    # behind what is located: nothing located is noise
    sensors = scored(sensor_places([s.place for s in places], experiment)) if places else []
    places += sensors
    springs = scored(spring_places(graph, [s.place for s in places]))
    return places + springs, springs, sensors


def without_companions(graph, scores) -> list:
    """`scores` without the law places (:mod:`diagnosis.law_places`) whose junction is scored too.

    A law that reaches a junction through a lever arm or a gear changes what that junction does,
    scaled by the moduli: the location scores the two alike and every kind fits both alike, so
    a law place would take a located place's slot and the catalogue would be fitted twice for
    nothing.  Such a law is its junction's *companion* instead (:func:`companions`)."""
    from .law_places import acts_on

    scored = {(s.place.kind, s.place.name) for s in scores}
    return [s for s in scores if s.place.kind != "law" or ("junction", acts_on(graph, s.place)) not in scored]


def companions(graph, places) -> dict:
    """Per located junction among `places`, the law places acting on it (:func:`without_companions`)."""
    from .law_places import acts_on, law_places

    located = {p.name for p in places if p.kind == "junction"}
    out = {}
    for law in law_places(graph):
        junction = acts_on(graph, law)
        if junction in located:
            out.setdefault(junction, []).append(law)
    return out


#: how many of a junction's best kinds are fitted at its companion law places
COMPANION_KINDS = 2


def companion_candidates(fits, laws_at: dict, make_candidates) -> list:
    """At each junction's companion law places (`laws_at`, from :func:`companions`), the
    candidates of the :data:`COMPANION_KINDS` kinds (with their regime) that fitted best at the
    junction: a law fits clearly better only where its own variables matter (a hysteresis whose
    level follows one muscle's pressure), and a tie goes to the junction (:func:`diagnosis.fit.choose`).

    `fits` are the round's fits; `make_candidates(place)` lists the catalogue's candidates at a place."""
    from .fit import single_fits_by_holdout

    ranked = single_fits_by_holdout(fits)
    out = []
    for junction, laws in laws_at.items():
        at = [f for f in ranked if f.candidate.place.kind == "junction" and f.candidate.place.name == junction]
        best = []
        for f in at:
            key = (f.candidate.kind, f.candidate.regime)
            if key not in best:
                best.append(key)
        for law in laws:
            offered = make_candidates(law)
            for key in best[:COMPANION_KINDS]:
                out += [c for c in offered if (c.kind, c.regime) == key][:1]
    return out
