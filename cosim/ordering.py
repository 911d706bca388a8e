"""Execution order of co-simulation components, and algebraic-loop detection.

The *port graph* has one node per signal ``"component.port"`` and an edge for
each connection ``source -> destination`` and, inside a component, for each
feedthrough pair ``input -> output``.  A cycle in it is an algebraic loop:
an output that depends on its own value at the same instant.

Without such a loop, components are ordered topologically (networkx) on the
*component graph*, which has an edge ``a -> b`` when an output of ``a``
drives a feedthrough input of ``b``.  Components can form a cycle there
without a loop between ports (``a.y1 -> b.u1 -> b.y1 -> a.u2 -> a.y2``);
such a strongly connected group is evaluated in repeated passes, as many as
its longest feedthrough chain needs (typically ``len(group)``), so that
every output is exact at the same instant.  Ties are broken by the order in
which the components were given.
"""
from __future__ import annotations

import networkx as nx

from cosim.errors import AlgebraicLoopError

__all__ = ["port_graph", "algebraic_loops", "execution_plan"]


def _comp(signal: str) -> str:
    return signal.split(".", 1)[0]


def port_graph(components, connections) -> nx.DiGraph:
    """The port graph; nodes carry ``kind`` (``"output"``/``"input"``) and ``rank``
    (position among all outputs, then all inputs, in component order)."""
    graph = nx.DiGraph()
    rank = 0
    for kind in ("output", "input"):
        for c in components:
            for p in (c.outputs if kind == "output" else c.inputs):
                graph.add_node(f"{c.name}.{p.name}", kind=kind, rank=rank)
                rank += 1
    graph.add_edges_from(connections)
    for c in components:
        graph.add_edges_from((f"{c.name}.{i}", f"{c.name}.{o}") for i, o in c.feedthrough)
    return graph


def algebraic_loops(ports: nx.DiGraph) -> list[list[str]]:
    """One loop per strongly connected group of ports, each in signal order from its
    first output, the groups ordered by that output."""
    loops = []
    for scc in nx.strongly_connected_components(ports):
        if len(scc) < 2:   # no port links to itself
            continue
        nodes = [u for u, _ in nx.find_cycle(ports.subgraph(scc))]
        outs = [i for i, s in enumerate(nodes) if ports.nodes[s]["kind"] == "output"]
        k = min(outs, key=lambda i: ports.nodes[nodes[i]]["rank"])
        loops.append(nodes[k:] + nodes[:k])
    return sorted(loops, key=lambda loop: ports.nodes[loop[0]]["rank"])


def execution_plan(components, connections) -> list[str]:
    """Component names in the order to call ``output`` (repeated for passes).

    Parameters
    ----------
    components : sequence of Component
    connections : sequence of (str, str)
        ``(source, destination)`` signal names, already checked.

    Returns
    -------
    list of str

    Raises
    ------
    AlgebraicLoopError
        Listing every loop; ``.ports`` is the first, in signal order.
    """
    ports = port_graph(components, connections)
    loops = algebraic_loops(ports)
    if loops:
        text = "\n".join(f"  {' -> '.join(loop)} -> {loop[0]}" for loop in loops)
        raise AlgebraicLoopError(
            f"algebraic loop{'s' if len(loops) > 1 else ''} through direct-feedthrough ports "
            f"(an output depends on its own value at the same instant):\n{text}\n"
            "break it with a component without feedthrough (a delay, a filter) or declare "
            "the true feedthrough of the components involved", ports=loops[0])
    index = {c.name: k for k, c in enumerate(components)}
    graph = nx.DiGraph()
    graph.add_nodes_from(range(len(components)))
    for src, dst in connections:
        if _comp(src) != _comp(dst) and ports.out_degree(dst) > 0:   # dst feeds through
            graph.add_edge(index[_comp(src)], index[_comp(dst)])
    cond = nx.condensation(graph)
    plan = []
    for node in nx.lexicographical_topological_sort(
            cond, key=lambda n: min(cond.nodes[n]["members"])):
        members = sorted(cond.nodes[node]["members"])
        names = [components[k].name for k in members]
        passes = _passes(names, ports, dict((d, s) for s, d in connections)) \
            if len(members) > 1 else 1
        plan.extend(names * passes)
    return plan


def _passes(names, ports: nx.DiGraph, source: dict) -> int:
    """Passes over a group evaluated in the order `names` until every output is exact.

    An output is exact in pass ``max(level(src) + [src's component is not earlier])``
    over the sources of its feedthrough inputs inside the group (1 without any).
    """
    rank = {n: r for r, n in enumerate(names)}
    level: dict[str, int] = {}
    for s in nx.topological_sort(ports):
        if _comp(s) not in rank or ports.nodes[s]["kind"] != "output":
            continue
        lv = 1
        for i in ports.predecessors(s):   # the feedthrough inputs of output s
            src = source.get(i)
            if src is not None and _comp(src) in rank:
                lv = max(lv, level[src] + (rank[_comp(src)] >= rank[_comp(s)]))
        level[s] = lv
    return max(level.values(), default=1)
