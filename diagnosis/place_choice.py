"""Which places' candidates are fitted, from graph location's scores.

Graph location (:mod:`diagnosis.graph_location`) ranks every junction, input and output by the
share of the residual a correction there explains.  The candidates of the best few are fitted
(:func:`located_places`), with the places location cannot tell from them: further places that
explain as much, and the inputs that drive a located junction directly (:func:`actuator_places`).
"""
from __future__ import annotations

from bondgraph.editing_inputs import expression_fields, mentions

from .catalogue_common import junction_elements
from .place import Place

__all__ = ["located_places", "actuator_places", "MIN_PLACE_SHARE", "PLACE_TIE"]

#: places whose correction explains less than this share of the residual get no candidates
MIN_PLACE_SHARE = 0.02


def actuator_places(graph, places, experiment) -> list:
    """The recorded inputs that drive a located junction directly, as input places not yet in
    `places`: a source named after the input, or an element bonded to the junction whose law
    reads it (a valve's command).  An actuator's lag, delay or limit there changes the junction's
    flow or effort exactly as a correction at the junction does, so graph location cannot rank
    the input above the junction: its candidates are fitted with the junction's."""
    recorded = [d.name for d in graph.inputs() if d.name in experiment.inputs]
    have = {(p.kind, p.name) for p in places}
    out = []
    for p in places:
        if p.kind != "junction":
            continue
        for element, _ in junction_elements(graph, p.name):
            entry = element.to_dict()
            for u in recorded:
                reads = element.name == u or any(mentions(c[k], u) for c, k in expression_fields(entry))
                if reads and ("input", u) not in have:
                    have.add(("input", u))
                    out.append(Place("input", u))
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
