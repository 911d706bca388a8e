"""The augmented graph of :mod:`diagnosis.graph_location`: an unknown source at each junction.

An effort source ``Se`` on a new bond into a 1-junction (a flow source ``Sf``
into a 0-junction), driven by a new model input ``d``, is an unknown extra
effort (flow) there.  The new source takes the junction's non-common variable
as given, so it never changes the causal assignment of the other bonds: one
graph with a source at every candidate junction serves all of them.
"""
from __future__ import annotations

import copy

from .errors import DiagnosisError

__all__ = ["augment", "junction_unit", "report_bond", "with_inputs"]


def _unique(graph, base: str, taken) -> str:
    used = set(graph.elements) | set(graph.bonds) | set(graph.names()) | set(taken)
    name, k = base, 1
    while name in used:
        k += 1
        name = f"{base}_{k}"
    return name


def augment(graph, junctions):
    """A copy of `graph` with an input-driven Se (1-junction) / Sf (0-junction) on each junction.

    Parameters
    ----------
    graph : BondGraph
    junctions : iterable of str
        Junction names.

    Returns
    -------
    (BondGraph, dict str -> str)
        The new graph and, per junction, the name of the input driving its source
        (``d_<junction>``, unit the junction's effort or flow unit).

    Raises
    ------
    DiagnosisError
        If `graph` is not a BondGraph.
    """
    from bondgraph import BondGraph, Se, Sf

    if not isinstance(graph, BondGraph):
        raise DiagnosisError("junction places need a BondGraph (a StateEquations has no junctions)")
    g = _copy_graph(graph)
    inputs, taken = {}, []
    for name in junctions:
        kind = g.elements[name].kind
        src_cls, word = (Se, "effort") if kind == "1" else (Sf, "flow")
        d = _unique(g, f"d_{name}", taken)
        src = _unique(g, f"extra_{word}_{name}", taken + [d])
        taken += [d, src]
        g.add(src_cls(src, 0.0, input=d, unit=junction_unit(graph, name),
                      description=f"unknown extra {word} at junction {name}"))
        g.connect(src, name, name=_unique(g, f"b_{src}", taken))
        inputs[name] = d
    return g, inputs


def _copy_graph(graph):
    """An independent copy of `graph` (elements deep-copied, derived caches left behind)."""
    g = copy.copy(graph)
    g._cache = None
    g.elements = copy.deepcopy(graph.elements)
    for attr in ("bonds", "outputs", "extra_inputs", "extra_params", "operating_point"):
        setattr(g, attr, dict(getattr(graph, attr)))
    g._changed()
    return g


def with_inputs(experiment, extra: dict, units: dict):
    """`experiment` with more recorded inputs.

    Parameters
    ----------
    experiment : Experiment
    extra : dict str -> ndarray, shape (n,)
        New inputs on the experiment's time grid.
    units : dict str -> str
        Their units.

    Returns
    -------
    Experiment
    """
    from .recording import Experiment

    return Experiment(experiment.t, {**experiment.inputs, **extra}, dict(experiment.outputs),
                      {**experiment.units, **units}, experiment.source, experiment.substeps)


def corrected(graph, experiment, junction: str, estimate=None):
    """``(graph, experiment, input)``: `graph` with an input-driven source on `junction`
    (:func:`augment`) and `experiment` with that input recorded as `estimate` (the location's
    correction there on the experiment's times; 0 where it is None, NaN or infinite), so that a
    run of the two is the nominal corrected there."""
    import numpy as np

    aug, inputs = augment(graph, [junction])
    d = inputs[junction]
    values = (np.zeros_like(experiment.t) if estimate is None
              else np.nan_to_num(np.asarray(estimate, float), nan=0.0, posinf=0.0, neginf=0.0))
    return aug, with_inputs(experiment, {d: values}, {d: junction_unit(graph, junction)}), d


def junction_unit(graph, junction: str) -> str:
    """Effort (1-junction) or flow (0-junction) unit at `junction`.

    From the domain of the nearest element with one (across other junctions, not
    across transformers), else from a declared output that is the junction's
    effort / flow on one of its bonds; "" when neither says.
    """
    from bondgraph.elements.base import unit_of

    word = "effort" if graph.elements[junction].kind == "1" else "flow"
    seen, todo = {junction}, [junction]
    while todo:
        name = todo.pop(0)
        for bond, _end in graph.bonds_of(name):
            for other in (bond.tail.element, bond.head.element):
                if other in seen:
                    continue
                seen.add(other)
                element = graph.elements[other]
                if element.kind in ("0", "1"):
                    todo.append(other)
                elif getattr(element, "domain", "generic") not in ("generic", None):
                    return unit_of(element.domain, word)
    # no domain around (equation-defined elements, transformers): an output that is this
    # junction's effort/flow on one of its bonds carries the unit
    letter = word[0]
    for bond, _end in graph.bonds_of(junction):
        for out in graph.outputs.values():
            if out.unit and str(out.expression).strip() == f"{letter}_{bond.name}":
                return out.unit
    return ""


def report_bond(graph, junction: str) -> str | None:
    """The bond to name a junction place by: its storage element's, else a named one, else the first."""
    bonds = [b for b, _ in graph.bonds_of(junction)]
    if not bonds:
        return None

    def other(b):
        return graph.elements[b.head.element if b.tail.element == junction else b.tail.element]

    for b in bonds:
        if other(b).kind in ("I", "C"):
            return b.name
    named = [b for b in bonds if not (b.name.startswith("bond") and b.name[4:].isdigit())]
    return (named or bonds)[0].name
