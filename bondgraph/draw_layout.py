"""Layout for :mod:`bondgraph.draw`: where element labels and small texts go.

Everything here works in inches of the figure at its natural size (1 layout
unit = 1 inch) and returns plain numbers; nothing here draws.  The rendering
module :mod:`bondgraph.draw` calls:

- :func:`element_box`: half-size of an element's label (text measured with
  matplotlib's font metrics, padding included);
- :func:`node_positions`: the centre of every element's label for one of
  :data:`bondgraph.draw.LAYOUTS`;
- :class:`FreeSpace` with :func:`subscript_spots`, :func:`label_spots` and
  :func:`port_spots`: collision-avoiding placement of junction names, bond
  names and port names.

Layered layout
--------------
Like graphviz's ``dot``, along the power direction: junctions, two-ports and
multiport elements form the *backbone* (:func:`_classify`), put in layers by
the longest path along their bonds' half-arrows, bonds closing a directed
cycle ignored (:func:`_layers`).  Layers are columns spaced so that the
widest labels and hanging elements of neighbouring columns clear each other
by 1.2 bond lengths (:func:`_place_component`); within a column each node
sits at the barycentre of its neighbours in the columns before it, then
after it, then before it again, each sweep the least-squares placement that
keeps the minimum spacing (:func:`_spread`).  One-port elements hang around
their node (:func:`_slots`, :func:`_offset`): sources to the left, others
above, below, then right or left, then diagonally, then on further rings.
Separate components are stacked top to bottom.

``"kamada_kawai"`` and ``"spring"`` (seed 7) come from networkx, scaled to a
mean bond length of 1.3 in; ``"auto"`` is ``"layered"`` unless element labels
overlap there and less so in ``"kamada_kawai"``.

Small texts
-----------
Each small text goes to the first candidate spot, in the order the ``*_spots``
functions list them, that collides least with the label boxes, lines, barbs,
strokes and small texts already placed (:meth:`FreeSpace.place`).
"""
from __future__ import annotations

import functools
import math

from .elements import SOURCE_KINDS, TWO_PORT_KINDS

__all__ = []  # private helpers of bondgraph.draw only

_SOURCES, _TWO_PORTS = SOURCE_KINDS, TWO_PORT_KINDS
_PREFIX = {"CField": "C", "IField": "I"}

# Sizes, inches at the natural figure size (1 layout unit = 1 inch) and points.
FONT_SIZES = {"element": 10.0, "junction": 13.0, "subscript": 7.0, "bond": 6.5, "port": 6.5}
_PAD = 0.045          # gap between a label and the bond end, in
_JPAD = 0.075         # the same around a junction digit, in
_BOND = 0.5           # length of a hanging element's bond, in
_GAP = 0.3            # extra clearance between neighbouring backbone nodes, in
_CLEAR = 0.03         # clearance kept around small texts (bond and junction names), in


# -- labels -------------------------------------------------------------------
def element_label(element) -> str:
    if element.ports is None or element.kind == "Eq":
        return element.kind if element.ports is None else element.name
    return f"{_PREFIX.get(element.kind, element.kind)}:{element.name}"


@functools.lru_cache(maxsize=4096)
def _text_size(text: str, size: float, *, bold=False) -> tuple:
    """Width and line height of `text` at `size` points, in."""
    from matplotlib.font_manager import FontProperties
    from matplotlib.textpath import TextToPath
    prop = FontProperties(size=size, weight="bold" if bold else "normal")
    width = TextToPath().get_text_width_height_descent(text, prop, ismath=False)[0]
    return width / 72.0, 1.2 * size / 72.0


def element_box(element) -> tuple:
    """Half-width and half-height of an element's label, padding included, in."""
    junction = element.ports is None
    w, h = _text_size(element_label(element), FONT_SIZES["junction" if junction else "element"], bold=junction)
    if junction:
        return w / 2 + _JPAD, h / 2 - 0.01
    pad = 0.09 if element.kind == "Eq" else _PAD
    return w / 2 + pad, h / 2 + pad / 2


# -- layered layout -----------------------------------------------------------
def _classify(graph):
    """Neighbours of each element, the backbone, and leaves (one-ports hung on it)."""
    nbrs = {n: [] for n in graph.elements}
    for b in graph.bonds.values():
        nbrs[b.tail.element].append((b.head.element, b))
        nbrs[b.head.element].append((b.tail.element, b))
    backbone = {n for n, e in graph.elements.items()
                if e.ports is None or len(e.ports) != 1 or len(nbrs[n]) != 1}
    for b in graph.bonds.values():  # two one-ports bonded directly: one of them anchors the other
        t, h = b.tail.element, b.head.element
        if t not in backbone and h not in backbone:
            backbone.add(t if graph.elements[h].kind in _SOURCES else h)
    leaves = {n: nbrs[n][0][0] for n in graph.elements if n not in backbone}
    return nbrs, backbone, leaves


def _layers(graph, backbone):
    """Layer and component of every backbone node: longest path along the power direction.

    Bonds closing a directed cycle are ignored; a node nothing feeds is pulled
    next to the nodes it feeds.  Layers start at 0 in each component.
    """
    import networkx as nx
    d = nx.DiGraph()
    d.add_nodes_from(n for n in graph.elements if n in backbone)
    d.add_edges_from((b.tail.element, b.head.element) for b in graph.bonds.values()
                     if b.tail.element in backbone and b.head.element in backbone)
    while not nx.is_directed_acyclic_graph(d):
        d.remove_edge(*nx.find_cycle(d)[-1][:2])
    order = list(nx.topological_sort(d))
    layer = {}
    for n in order:
        layer[n] = max((layer[p] + 1 for p in d.predecessors(n)), default=0)
    for n in reversed(order):
        if d.in_degree(n) == 0 and d.out_degree(n):
            layer[n] = min(layer[m] for m in d.successors(n)) - 1
    rank = {n: i for i, n in enumerate(graph.elements)}
    comp = {}
    for c, nodes in enumerate(sorted(nx.weakly_connected_components(d), key=lambda ns: min(rank[n] for n in ns))):
        low = min(layer[n] for n in nodes)
        for n in nodes:
            comp[n], layer[n] = c, layer[n] - low
    return layer, comp


def _slots(graph, nbrs, backbone, leaves, layer) -> dict:
    """Direction (degrees) and ring of each hanging element around its backbone node."""
    out = {}
    for node in (n for n in graph.elements if n in backbone):
        taken = set()
        for m, _ in nbrs[node]:
            if m in backbone:
                d = layer[m] - layer[node]
                taken |= {180} if d < 0 else {0} if d > 0 else {90, 270}
        hung = [m for m, _ in nbrs[node] if leaves.get(m) == node]
        hung.sort(key=lambda m: graph.elements[m].kind not in _SOURCES)
        used: set = set()
        for k, m in enumerate(hung):
            first = (180, 0, 90, 270) if graph.elements[m].kind in _SOURCES else (90, 270, 0, 180)
            order = [a for a in first if a not in taken] + [315, 45, 225, 135] + [a for a in first if a in taken]
            if k % 8 == 0:  # every direction used: start a ring further out
                used = set()
            angle = next(a for a in order if a not in used)
            used.add(angle)
            out[m] = (angle, 1 + k // 8)
    return out


def _offset(angle, ring, node_box, leaf_box) -> tuple:
    """Centre of a hanging element's label relative to its node, in."""
    (w0, h0), (w1, h1) = node_box, leaf_box
    if ring > 1:  # between the directions of the ring inside, so that bonds pass between its labels
        a, r = math.radians(angle + 22.5), ring * (max(w0, h0) + max(w1, h1) + _BOND)
        return r * math.cos(a), r * math.sin(a)
    sx = 1 if angle in (0, 45, 315) else -1 if angle in (135, 180, 225) else 0
    sy = 1 if angle in (45, 90, 135) else -1 if angle in (225, 270, 315) else 0
    if sx and sy:
        return sx * (w0 + w1 + 0.2 * ring), sy * (h0 + h1 + 0.35 * ring)
    if sy:
        return 0.0, sy * (h0 + h1 + _BOND * ring)
    return sx * (w0 + w1 + 1.2 * _BOND * ring), 0.0


def _extents(backbone, leaves, slots, boxes):
    """Offsets of hanging elements and (left, right, down, up) extent of each backbone node, in."""
    offsets = {m: _offset(*slots[m], boxes[leaves[m]], boxes[m]) for m in leaves}
    ext = {n: [boxes[n][0], boxes[n][0], boxes[n][1], boxes[n][1]] for n in backbone}
    for m, (dx, dy) in offsets.items():
        e, (w, h) = ext[leaves[m]], boxes[m]
        e[0], e[1] = max(e[0], w - dx), max(e[1], w + dx)
        e[2], e[3] = max(e[2], h - dy), max(e[3], h + dy)
    return offsets, ext


def _spread(desired, seps) -> list:
    """Heights closest (least squares) to `desired`, top first, with ``y[i] - y[i+1] >= seps[i]``.

    With ``z_i = y_i + S_i`` (``S_i`` the cumulative spacing) the constraint
    is ``z`` non-increasing: pool adjacent violators.
    """
    cum = [0.0]
    for s in seps:
        cum.append(cum[-1] + s)
    blocks = []  # [sum, count]
    for d, s in zip(desired, cum):
        blocks.append([d + s, 1])
        while len(blocks) > 1 and blocks[-2][0] / blocks[-2][1] < blocks[-1][0] / blocks[-1][1]:
            total, count = blocks.pop()
            blocks[-1][0] += total
            blocks[-1][1] += count
    z = [total / count for total, count in blocks for _ in range(count)]
    return [zi - s for zi, s in zip(z, cum)]


def _place_component(nodes, layer, nbrs, ext, rank) -> dict:
    """Positions of one component's backbone: x by layer, y by barycentre sweeps."""
    by_layer: dict = {}
    for n in nodes:
        by_layer.setdefault(layer[n], []).append(n)
    last = max(by_layer)
    xs, x = {}, 0.0
    for k in range(last + 1):
        xs[k] = x
        if k < last:
            x += max(ext[n][1] for n in by_layer[k]) + max(ext[n][0] for n in by_layer[k + 1]) + _BOND * 1.2
    y: dict = {}
    sweeps = [range(last + 1), range(last, -1, -1), range(last + 1)]  # down, up, down
    for sweep, layers in enumerate(sweeps):
        for k in layers:
            _place_layer(by_layer[k], y, nbrs, ext, rank,
                         lambda m, k=k, up=sweep == 1: m in y and (layer[m] > k if up else layer[m] < k))
    return {n: (xs[layer[n]], y[n]) for n in nodes}


def _place_layer(nodes, y, nbrs, ext, rank, counts) -> None:
    """Put one layer's nodes at the mean height of their `counts` neighbours, keeping their spacing."""
    desired = {}
    for n in nodes:
        ys = [y[m] for m, _ in nbrs[n] if counts(m)]
        desired[n] = sum(ys) / len(ys) if ys else y.get(n, 0.0)
    order = sorted(nodes, key=lambda n: (-desired[n], rank[n]))
    seps = [ext[a][2] + ext[b][3] + _GAP for a, b in zip(order, order[1:])]
    for n, value in zip(order, _spread([desired[n] for n in order], seps)):
        y[n] = value


def _layered(graph, boxes) -> dict:
    """Layered (left-to-right) positions of every element, in."""
    nbrs, backbone, leaves = _classify(graph)
    layer, comp = _layers(graph, backbone)
    offsets, ext = _extents(backbone, leaves, _slots(graph, nbrs, backbone, leaves, layer), boxes)
    rank = {n: i for i, n in enumerate(graph.elements)}
    pos, top = {}, 0.0
    for c in sorted(set(comp.values())):
        nodes = [n for n in graph.elements if comp.get(n) == c]
        local = _place_component(nodes, layer, nbrs, ext, rank)
        high = max(y + ext[n][3] for n, (_, y) in local.items())
        low = min(y - ext[n][2] for n, (_, y) in local.items())
        left = min(x - ext[n][0] for n, (x, _) in local.items())
        for n, (x, y) in local.items():
            pos[n] = (x - left, y - high + top)
        top -= high - low + 2 * _GAP
    for m, (dx, dy) in offsets.items():
        x, y = pos[leaves[m]]
        pos[m] = (x + dx, y + dy)
    return pos


# -- layout selection ---------------------------------------------------------
def node_positions(graph, boxes, layout) -> dict:
    """Centre of every element's label for `layout`.

    Parameters
    ----------
    graph : BondGraph
    boxes : dict str -> (float, float)
        Half-width and half-height of each element's label (:func:`element_box`), in.
    layout : {"auto", "layered", "kamada_kawai", "spring"}
        ``"auto"`` is ``"layered"`` unless labels overlap there and fewer
        pairs overlap with ``"kamada_kawai"``.

    Returns
    -------
    dict str -> (float, float)
        Label centres, in.
    """
    pos = _layered(graph, boxes) if layout in ("auto", "layered") else _networkx_layout(graph, layout)
    if layout == "auto" and _collisions(pos, boxes) and len(graph.bonds):
        alternative = _networkx_layout(graph, "kamada_kawai")
        if _collisions(alternative, boxes) < _collisions(pos, boxes):
            pos = alternative
    return pos


def _collisions(pos, boxes) -> int:
    """Number of pairs of element labels that overlap."""
    rects = [(x - boxes[n][0], y - boxes[n][1], x + boxes[n][0], y + boxes[n][1]) for n, (x, y) in pos.items()]
    return sum(_overlap(a, b) for i, a in enumerate(rects) for b in rects[i + 1:])


def _networkx_layout(graph, layout) -> dict:
    """Positions from networkx (seeded), scaled to a mean bond length of 1.3 in."""
    import networkx as nx
    g = nx.Graph()
    g.add_nodes_from(graph.elements)
    g.add_edges_from((b.tail.element, b.head.element) for b in graph.bonds.values())
    if layout == "kamada_kawai" and g.number_of_edges():
        raw = nx.kamada_kawai_layout(g)
    else:
        raw = nx.spring_layout(g, seed=7)
    lengths = [math.dist(raw[a], raw[b]) for a, b in g.edges] or [1.0]
    scale = 1.3 / max(sum(lengths) / len(lengths), 1e-9)
    return {n: (float(raw[n][0]) * scale, float(raw[n][1]) * scale) for n in graph.elements}


# -- small texts: collision-avoiding placement --------------------------------
def _align(o) -> tuple:
    """Text alignment that puts a label on the side `o` (unit vector) points to."""
    ha = "left" if o[0] > 0.35 else "right" if o[0] < -0.35 else "center"
    va = "bottom" if o[1] > 0.35 else "top" if o[1] < -0.35 else "center"
    return ha, va


def subscript_spots(xy, box, others) -> list:
    """Candidate (anchor, ha, va) for a junction's name: diagonals clear of its bonds first, nearest first."""
    angles = [math.degrees(math.atan2(y - xy[1], x - xy[0])) % 360 for x, y in others]

    def clearance(a):
        return min((min(abs(a - b), 360 - abs(a - b)) for b in angles), default=180)
    spots = []
    for diagonal in sorted((315, 45, 225, 135), key=lambda a: -clearance(a)):  # stable: lower right first
        sx, sy = (1 if diagonal in (315, 45) else -1), (1 if diagonal in (45, 135) else -1)
        ha, va = ("left" if sx > 0 else "right"), ("bottom" if sy > 0 else "top")
        digit = box[0] - _JPAD  # half-width of the digit itself
        for dx, dy in ((digit + 0.015, 0.0), (box[0], 0.04), (box[0], box[1]), (box[0] + 0.05, box[1] + 0.05)):
            spots.append(((xy[0] + sx * dx, xy[1] + sy * dy), ha, va))
    return spots


def label_spots(start, end, n) -> list:
    """Candidate (anchor, ha, va) for a bond name: beside the bond, middle first, right side first."""
    spots = []
    for gap in (0.04, 0.15):  # next to the line, then a little further out
        for t in (0.5, 0.35, 0.65, 0.2, 0.8):
            for side in (-1, 1):
                o = (side * n[0], side * n[1])
                xy = (start[0] + t * (end[0] - start[0]) + gap * o[0], start[1] + t * (end[1] - start[1]) + gap * o[1])
                spots.append((xy, *_align(o)))
    return spots


def port_spots(graph, bond, start, end, d, n) -> list:
    """Port names at the ends of a bond that belong to multiport elements (fields, Eq)."""
    out = []
    for port, p, sign in ((bond.tail, start, 1), (bond.head, end, -1)):
        element = graph.elements[port.element]
        if element.ports is None or len(element.ports) < 2 or element.kind in _TWO_PORTS:
            continue
        spots = []
        for along in (0.05, 0.15):
            for side in (-1, 1):
                o = (side * n[0], side * n[1])
                xy = (p[0] + sign * d[0] * along + 0.04 * o[0], p[1] + sign * d[1] * along + 0.04 * o[1])
                away = (o[0] + sign * d[0], o[1] + sign * d[1])  # beside the bond and away from the element
                spots.append((xy, *_align((away[0] / math.sqrt(2), away[1] / math.sqrt(2)))))
        out.append((port.port, spots))
    return out


def _text_rect(xy, text, size, ha, va) -> tuple:
    """(x0, y0, x1, y1) of `text` at `size` points anchored at `xy` with the given alignment, in."""
    w, h = _text_size(text, size)
    x0 = xy[0] - (0.0 if ha == "left" else w if ha == "right" else w / 2)
    y0 = xy[1] - (0.0 if va == "bottom" else h if va == "top" else h / 2)
    return (x0, y0, x0 + w, y0 + h)


def _overlap(a, b, tol=0.005) -> bool:
    return a[0] < b[2] - tol and b[0] < a[2] - tol and a[1] < b[3] - tol and b[1] < a[3] - tol


class FreeSpace:
    """What is already on the page (label boxes, points along lines); finds free spots for small labels."""

    def __init__(self, rects, segments):
        import numpy as np
        self.rects = list(rects)
        pts = [(a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]))
               for a, b in segments for t in np.linspace(0.0, 1.0, max(2, int(math.dist(a, b) / 0.03) + 1))]
        self.points = np.array(pts, dtype=float).reshape(-1, 2)

    def cost(self, r, ignore=None) -> int:
        m = _CLEAR
        r, p = (r[0] - m, r[1] - m, r[2] + m, r[3] + m), self.points
        inside = (p[:, 0] > r[0]) & (p[:, 0] < r[2]) & (p[:, 1] > r[1]) & (p[:, 1] < r[3])
        return int(inside.sum()) + 100 * sum(_overlap(r, q) for q in self.rects if q != ignore)

    def place(self, spots, text, size, *, ignore=None) -> tuple:
        """The first spot with the least collisions, as (anchor, ha, va, box); the box is then taken.

        `ignore` is a box the text may overlap (a junction's own digit box).
        """
        best = min(spots, key=lambda s: self.cost(_text_rect(s[0], text, size, s[1], s[2]), ignore))
        rect = _text_rect(best[0], text, size, best[1], best[2])
        self.rects.append(rect)
        return (*best, rect)
