"""A bond graph's dict form, the content of its JSON file (``docs/json-schema.md``).

The writing half of :mod:`bondgraph.io_json`, apart so that
:meth:`BondGraph.to_dict <bondgraph.graph.BondGraph.to_dict>` needs no import of
the reader (which builds graphs, so imports :mod:`bondgraph.graph`).
"""
from __future__ import annotations

import numbers
from typing import TYPE_CHECKING

if TYPE_CHECKING:   # annotations only: graph.py imports this module
    from .graph import BondGraph

__all__ = ["FORMAT", "VERSION", "graph_to_dict"]

#: Value of the top-level ``"format"`` key.
FORMAT = "bondcosim-graph"
#: Version of the format :mod:`bondgraph.io_json` writes and reads.
VERSION = 1


def graph_to_dict(graph: BondGraph) -> dict:
    """The JSON-ready description of `graph` (see ``docs/json-schema.md``).

    Parameters
    ----------
    graph : BondGraph

    Returns
    -------
    dict
        Plain dicts, lists, strings and numbers, keys in the documented order.
    """
    return {
        "format": FORMAT,
        "version": VERSION,
        "name": graph.name,
        "description": graph.description,
        "elements": [element.to_dict() for element in graph.elements.values()],
        "bonds": [{"name": b.name, "tail": [b.tail.element, b.tail.port], "head": [b.head.element, b.head.port]}
                  for b in graph.bonds.values()],
        "inputs": [_input_entry(d) for d in graph.extra_inputs.values()],
        "parameters": [p.to_dict() for p in graph.extra_params.values()],
        "outputs": [{"name": o.name, "expression": str(o.expression), "unit": o.unit,
                     "description": o.description} for o in graph.outputs.values()],
        "operating_point": {k: _plain_number(v) for k, v in graph.operating_point.items()},
        **({"guards": {g.name: g.to_dict() for g in graph.extra_guards.values()}}
           if graph.extra_guards else {}),
    }


def _input_entry(decl) -> dict:
    entry = {"name": decl.name, "default": decl.default, "unit": decl.unit, "description": decl.description}
    if decl.delay is not None:
        entry.update(delay_of=decl.delay.source, delay=decl.delay.time)
        if decl.delay.before is not None:
            entry["before"] = decl.delay.before
    return entry


def _plain_number(value):
    is_real = isinstance(value, numbers.Real) and not isinstance(value, bool)
    return float(value) if is_real else value
