"""Drawing bond graphs: power half-arrows and causal strokes, with matplotlib.

:func:`draw` renders a :class:`~bondgraph.graph.BondGraph` in the usual
textbook style: elements as text labels (``Se:F``, ``I:m``, ``TF:n``,
junctions ``0``/``1`` with their name as a subscript, equation-defined
elements as a boxed name), bonds as lines with the power half-arrow at the
head end and, when causality can be assigned, the causal stroke at the end
next to the element that receives the effort.

:func:`draw_geometry` computes everything :func:`draw` puts on the page (label
boxes, bond end points, half-arrow barbs, strokes) as plain numbers, so that
the drawing can be tested without comparing images.  Coordinates are inches
of the figure at its natural size.

Conventions
-----------
- The half-arrow barb is drawn on the *left* of the bond, looking from tail
  to head (above a bond drawn left to right), at the head end.
- The causal stroke is perpendicular to the bond at
  :meth:`~bondgraph.causality.CausalAssignment.stroke_end`; it is red on the
  bond of a storage element in derivative causality and orange on a bond
  whose causality was chosen arbitrarily (an algebraic loop).

Layout
------
Computed in :mod:`bondgraph.draw_layout`.  ``"layered"`` reads left to right along the power direction, like
graphviz's ``dot``: junctions, two-ports and multiport elements form the
*backbone*, put in layers by the longest path along their bonds' half-arrows
(bonds closing a directed cycle ignored); within a layer each node sits at
the barycentre of its neighbours in the layers before it, then after it,
then before it again (three sweeps; each the least-squares placement that
keeps the minimum spacing).  One-port elements hang around their node:
sources to the left, others above, below, then right or left, then
diagonally.  ``"kamada_kawai"`` and ``"spring"`` (seeded) use networkx.
``"auto"`` is ``"layered"`` unless element labels overlap there and less so
in ``"kamada_kawai"``.  Small texts (bond names, junction names, port
names) go to the first spot near their anchor that collides with nothing
already drawn.
"""
from __future__ import annotations

import math
import textwrap
from dataclasses import dataclass
from pathlib import Path

from .draw_layout import (FONT_SIZES, FreeSpace, element_box, element_label, label_spots, port_spots, node_positions,
                          subscript_spots)
from .errors import ArgumentError, BondcosimError, CausalityError

__all__ = ["draw", "draw_geometry", "DrawingGeometry", "ElementGeometry", "BondGeometry", "LAYOUTS"]

#: Accepted values of the `layout` option.
LAYOUTS = ("auto", "layered", "kamada_kawai", "spring")
_SUFFIXES = (".png", ".svg", ".pdf")

# Sizes, inches at the natural figure size (1 layout unit = 1 inch).
_BARB = (0.13, 0.075)  # half-arrow barb: length along the bond, offset to its side, in
_STROKE = 0.085       # half-length of a causal stroke, in
_COLORS = {"": "black", "derivative": "red", "arbitrary": "darkorange", "conflict": "darkorange"}


@dataclass(frozen=True)
class ElementGeometry:
    """Where one element's label goes.

    Attributes
    ----------
    name, kind : str
    label : str
        The text drawn (``"I:m"``, ``"1"``, the name of an Eq element).
    xy : (float, float)
        Centre of the label, in.
    box : (float, float, float, float)
        ``(x0, y0, x1, y1)`` of the label, bonds end at its edge, in.
    subscript : ((float, float), str, str, tuple) or None
        Junction name: anchor, horizontal and vertical alignment, and its box
        ``(x0, y0, x1, y1)``, placed on the diagonal clear of the bonds.
    status : {"", "derivative", "conflict"}
        Storage in derivative causality, or an element of a causal conflict.
    """

    name: str
    kind: str
    label: str
    xy: tuple
    box: tuple
    subscript: tuple | None = None
    status: str = ""


@dataclass(frozen=True)
class BondGeometry:
    """Where one bond, its half-arrow and its causal stroke go (inches).

    Attributes
    ----------
    name, tail, head : str
        Bond name and the elements at its tail and head; power is positive
        from tail to head.
    start, end : (float, float)
        The drawn line, from the tail element's label edge to the head's.
    barb : ((float, float), (float, float))
        The half-arrow: from the tip (= `end`) to the barb's free end.
    side : str
        ``"left"``: the barb is on the left looking from tail to head.
    stroke_end : {"tail", "head"} or None
        End carrying the causal stroke (``None``: causality not drawn).
    stroke : ((float, float), (float, float)) or None
        The stroke, perpendicular to the bond through `start` or `end`.
    status : {"", "derivative", "arbitrary"}
        Bond of a storage element in derivative causality, or a bond whose
        causality was chosen arbitrarily (algebraic loop).
    label : ((float, float), str, str, tuple)
        Bond name: anchor, horizontal and vertical alignment, and its box;
        beside the bond, at the first spot (middle first) that collides
        with no other label, line, barb or stroke.
    ports : tuple of (str, (float, float), str, str, tuple)
        Port names of multiport elements (fields, Eq) next to the bond's
        ends, placed the same way.
    """

    name: str
    tail: str
    head: str
    start: tuple
    end: tuple
    barb: tuple
    side: str
    stroke_end: str | None
    stroke: tuple | None
    status: str
    label: tuple
    ports: tuple = ()


@dataclass(frozen=True)
class DrawingGeometry:
    """Everything :func:`draw` draws, as numbers (inches at natural size).

    Attributes
    ----------
    elements : dict str -> ElementGeometry
    bonds : dict str -> BondGeometry
    bounds : (float, float, float, float)
        ``(x0, y0, x1, y1)`` enclosing every label, with a margin.
    notes : tuple of str
        Why causality is not drawn (each causal conflict), else empty.
    derivative : tuple of (str, str)
        (element, bond) of storage in derivative causality.
    arbitrary : tuple of str
        Elements and bonds whose causality was chosen arbitrarily.
    """

    elements: dict
    bonds: dict
    bounds: tuple
    notes: tuple = ()
    derivative: tuple = ()
    arbitrary: tuple = ()


# -- public API ---------------------------------------------------------------
def draw(graph, path=None, *, layout="auto", causality=True, ax=None, title=None, figsize=None):
    """Draw `graph` with power half-arrows and causal strokes.

    Parameters
    ----------
    graph : BondGraph
        The graph (it need not be complete: problems are shown, not raised).
    path : str or Path, optional
        Save the figure there; the suffix chooses the format (``.png`` at
        150 dpi, ``.svg``, ``.pdf``).
    layout : {"auto", "layered", "kamada_kawai", "spring"}
        Placement of the elements (see the module docstring).
    causality : bool
        Draw causal strokes.  If causality cannot be assigned, the graph is
        drawn without them and the reasons are written under the title.
    ax : matplotlib Axes, optional
        Draw into these axes (fonts scale with them) instead of a new figure.
    title : str, optional
        Title; the graph's name by default, ``""`` for none.
    figsize : (float, float), optional
        Figure size, in; by default it follows the layout's extent.

    Returns
    -------
    matplotlib.figure.Figure

    Raises
    ------
    ValueError
        Unknown `layout` or file suffix.
    TypeError
        Any other keyword (Python's own check).

    Notes
    -----
    Without `path` or `ax` the figure is made with pyplot (so that it shows
    in interactive sessions); with `path` it is a bare Agg figure that
    pyplot does not track.  Artists carry ids: ``bond:<name>``,
    ``barb:<name>``, ``stroke:<name>``, ``bondname:<name>``,
    ``element:<name>``.

    Examples
    --------
    >>> import os, tempfile
    >>> from plants.library import mass_spring_damper
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     fig = draw(mass_spring_damper(), os.path.join(tmp, "msd.png"))
    >>> sorted(a.get_gid() for a in fig.axes[0].lines if a.get_gid().startswith("stroke:"))
    ['stroke:bond1', 'stroke:bond2', 'stroke:bond3', 'stroke:bond4']
    """
    if path is not None and Path(path).suffix.lower() not in _SUFFIXES:
        raise ArgumentError(f"cannot save a drawing as {Path(path).name!r}: the file name must end in "
                         f"{', '.join(_SUFFIXES)}")
    geometry = draw_geometry(graph, layout=layout, causality=causality)
    title = graph.name if title is None else title
    fig, ax, scale = _axes(geometry, ax, figsize, title, interactive=path is None)
    for b in geometry.bonds.values():
        _draw_bond(ax, b, scale)
    for e in geometry.elements.values():
        _draw_element(ax, e, scale)
    _draw_notes(ax, geometry, title, scale)
    if path is not None:
        png = Path(path).suffix.lower() == ".png"
        fig.savefig(path, dpi=150 if png else None, facecolor="white")
    return fig


def draw_geometry(graph, *, layout="auto", causality=True) -> DrawingGeometry:
    """Compute the drawing of `graph` as numbers (no figure is made).

    Parameters
    ----------
    graph : BondGraph
    layout : {"auto", "layered", "kamada_kawai", "spring"}
    causality : bool
        Assign causality and place the strokes.

    Returns
    -------
    DrawingGeometry

    Examples
    --------
    >>> from plants.library import mass_spring_damper
    >>> geometry = draw_geometry(mass_spring_damper())
    >>> [(b.name, b.tail, b.head, b.stroke_end) for b in geometry.bonds.values()]  # doctest: +NORMALIZE_WHITESPACE
    [('bond1', 'F', 'v_mass', 'head'), ('bond2', 'v_mass', 'm', 'head'),
     ('bond3', 'v_mass', 'b', 'tail'), ('bond4', 'v_mass', 'k', 'tail')]
    """
    if layout not in LAYOUTS:
        raise ArgumentError(f"unknown layout {layout!r}; expected one of {', '.join(LAYOUTS)}")
    assignment, notes, conflicted = _causality(graph, causality)
    derivative = tuple(assignment.derivative) if assignment else ()
    arbitrary = tuple(assignment.arbitrary) if assignment else ()
    boxes = {n: element_box(e) for n, e in graph.elements.items()}
    pos = node_positions(graph, boxes, layout)
    status = {n: "conflict" for n in conflicted}
    status.update({n: "derivative" for n, _ in derivative})
    elements = {n: _element_geometry(graph, n, pos, boxes[n], status.get(n, "")) for n in graph.elements}
    bonds = _bond_geometries(graph, elements, assignment, derivative, arbitrary)
    return DrawingGeometry(elements, bonds, _bounds(elements, bonds), notes, derivative, arbitrary)


# -- causality ----------------------------------------------------------------
def _causality(graph, wanted):
    """(assignment or None, note lines, names of elements in conflict)."""
    if not wanted:
        return None, (), ()
    try:
        return graph.causality(), (), ()
    except CausalityError as exc:
        lines = tuple(f"causal conflict: {c}" for c in exc.conflicts) or (str(exc),)
        names = tuple(n for c in exc.conflicts for n in getattr(c, "elements", (c.element,)))  # Conflict-like
        return None, lines, names
    except BondcosimError as exc:  # an incomplete graph or a bad expression: draw what there is
        problems = getattr(exc, "problems", None) or str(exc).splitlines()
        return None, ("causality not assigned:", *(f"- {p.strip().lstrip('- ')}" for p in problems)), ()


# -- geometry -----------------------------------------------------------------
def _element_geometry(graph, name, pos, box, status) -> ElementGeometry:
    element, (x, y), (w, h) = graph.elements[name], pos[name], box
    return ElementGeometry(name, element.kind, element_label(element), (x, y), (x - w, y - h, x + w, y + h), None, status)


def _exit(box_half, d) -> float:
    """Distance from a label's centre to its box edge along unit direction `d`."""
    w, h = box_half
    tx = w / abs(d[0]) if abs(d[0]) > 1e-12 else math.inf
    ty = h / abs(d[1]) if abs(d[1]) > 1e-12 else math.inf
    return min(tx, ty)


def _segment(a, b, offset):
    """Trimmed segment between label boxes `a` and `b`, shifted sideways by `offset`."""
    (xa, ya), (xb, yb) = a.xy, b.xy
    length = math.hypot(xb - xa, yb - ya) or 1e-9
    d = ((xb - xa) / length, (yb - ya) / length)
    n = (-d[1], d[0])  # left normal
    halves = [((e.box[2] - e.box[0]) / 2, (e.box[3] - e.box[1]) / 2) for e in (a, b)]
    ta, tb = _exit(halves[0], d), _exit(halves[1], d)
    if ta + tb > length - 0.1:  # labels nearly touch: keep a short visible bond
        ta = tb = max(0.0, (length - 0.1) / 2)
    shift = (n[0] * offset, n[1] * offset)
    start = (xa + d[0] * ta + shift[0], ya + d[1] * ta + shift[1])
    end = (xb - d[0] * tb + shift[0], yb - d[1] * tb + shift[1])
    return start, end, d, n


def _bond_geometries(graph, elements, assignment, derivative, arbitrary) -> dict:
    """Lines, half-arrows and strokes of every bond, then free spots for the names of
    junctions (`elements` is updated) and bonds."""
    pairs: dict = {}
    for b in graph.bonds.values():
        pairs.setdefault(frozenset((b.tail.element, b.head.element)), []).append(b.name)
    dbonds = {bond for _, bond in derivative}
    abonds = set(arbitrary) | {b.name for b in graph.bonds.values()
                               if b.tail.element in arbitrary or b.head.element in arbitrary}
    lines = {}
    for b in graph.bonds.values():
        group = pairs[frozenset((b.tail.element, b.head.element))]
        offset = (group.index(b.name) - (len(group) - 1) / 2) * 0.16
        start, end, d, n = _segment(elements[b.tail.element], elements[b.head.element], offset)
        seg = math.dist(start, end)
        blen, bw = min(_BARB[0], 0.4 * seg), min(_BARB[1], 0.25 * seg)
        barb = (end, (end[0] - d[0] * blen + n[0] * bw, end[1] - d[1] * blen + n[1] * bw))
        stroke_end = stroke = None
        if assignment is not None and b.name in assignment.effort_by:
            stroke_end = assignment.stroke_end(b)
            p = end if stroke_end == "head" else start
            stroke = ((p[0] + n[0] * _STROKE, p[1] + n[1] * _STROKE), (p[0] - n[0] * _STROKE, p[1] - n[1] * _STROKE))
        status = "derivative" if b.name in dbonds else "arbitrary" if b.name in abonds and stroke else ""
        lines[b.name] = (start, end, d, n, barb, stroke_end, stroke, status)
    free = FreeSpace([e.box for e in elements.values()],
                 [seg for s, e, _, _, barb, _, stroke, _ in lines.values() for seg in ((s, e), barb, stroke) if seg])
    for name, e in elements.items():
        if graph.elements[name].ports is None:
            others = [elements[b.head.element if b.tail.element == name else b.tail.element].xy
                      for b in graph.bonds.values() if name in (b.tail.element, b.head.element)]
            box = ((e.box[2] - e.box[0]) / 2, (e.box[3] - e.box[1]) / 2)
            sub = free.place(subscript_spots(e.xy, box, others), name, FONT_SIZES["subscript"], ignore=e.box)
            elements[name] = ElementGeometry(e.name, e.kind, e.label, e.xy, e.box, sub, e.status)
    ports = {b.name: tuple((port, *free.place(spots, port, FONT_SIZES["port"]))
                           for port, spots in port_spots(graph, b, *lines[b.name][:4])) for b in graph.bonds.values()}
    out = {}
    for b in graph.bonds.values():
        start, end, d, n, barb, stroke_end, stroke, status = lines[b.name]
        label = free.place(label_spots(start, end, n), b.name, FONT_SIZES["bond"])
        out[b.name] = BondGeometry(b.name, b.tail.element, b.head.element, start, end, barb, "left", stroke_end,
                                   stroke, status, label, ports[b.name])
    return out


def _bounds(elements, bonds) -> tuple:
    """Box around every label, line and small text, with a margin."""
    rects = [e.box for e in elements.values()] + [e.subscript[3] for e in elements.values() if e.subscript]
    rects += [b.label[3] for b in bonds.values()] + [p[4] for b in bonds.values() for p in b.ports]
    if not rects:
        return (0.0, 0.0, 1.0, 1.0)
    m = 0.25
    return (min(r[0] for r in rects) - m, min(r[1] for r in rects) - m,
            max(r[2] for r in rects) + m, max(r[3] for r in rects) + m)


# -- rendering ----------------------------------------------------------------
def _axes(geometry, ax, figsize, title, *, interactive):
    """The axes to draw in and the font scale (actual inches per layout inch)."""
    x0, y0, x1, y1 = geometry.bounds
    width, height = x1 - x0, y1 - y0
    top = (0.45 if title else 0.1) + 0.16 * _note_lines(geometry, width)
    bottom = 0.1 + 0.2 * len(_legend_entries(geometry))
    if ax is None:
        natural = (max(width, 3.0), height + top + bottom)
        size = tuple(figsize) if figsize is not None else _capped(natural)
        if interactive:
            import matplotlib.pyplot as plt
            fig = plt.figure(figsize=size)
        else:
            from matplotlib.backends.backend_agg import FigureCanvasAgg
            from matplotlib.figure import Figure
            fig = Figure(figsize=size)
            FigureCanvasAgg(fig)
        k = min(size[0] / natural[0], size[1] / natural[1])
        ax = fig.add_axes([0.0, bottom * k / size[1], 1.0, 1.0 - (top + bottom) * k / size[1]])
    fig = ax.figure
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect("equal", adjustable="box")
    ax.set_axis_off()
    box = ax.get_position()
    w_in, h_in = box.width * fig.get_figwidth(), box.height * fig.get_figheight()
    scale = max(min(w_in / width, h_in / height), 0.35)
    return fig, ax, scale


def _capped(size) -> tuple:
    """Natural figure size, shrunk (same aspect) to at most 40 x 30 in."""
    k = min(1.0, 40.0 / size[0], 30.0 / size[1])
    return (size[0] * k, size[1] * k)


def _draw_bond(ax, b: BondGeometry, scale):
    color = _COLORS[b.status] if b.status else "black"
    lw = 1.1 * scale
    (xs, ys), (xe, ye) = b.start, b.end
    ax.plot([xs, xe], [ys, ye], color="black", lw=lw, solid_capstyle="butt", gid=f"bond:{b.name}")
    (tx, ty), (bx, by) = b.barb
    ax.plot([tx, bx], [ty, by], color="black", lw=lw, solid_capstyle="round", gid=f"barb:{b.name}")
    if b.stroke is not None:
        (ax_, ay), (cx, cy) = b.stroke
        ax.plot([ax_, cx], [ay, cy], color=color, lw=(2.0 if b.status else 1.4) * scale,
                solid_capstyle="butt", gid=f"stroke:{b.name}")
    (lx, ly), ha, va, _ = b.label
    ax.text(lx, ly, b.name, fontsize=FONT_SIZES["bond"] * scale, color="0.45", ha=ha, va=va, gid=f"bondname:{b.name}")
    for text, (px, py), ha, va, _ in b.ports:
        ax.text(px, py, text, fontsize=FONT_SIZES["port"] * scale, color="navy", style="italic", ha=ha, va=va)


def _draw_element(ax, e: ElementGeometry, scale):
    color = _COLORS[e.status]
    x, y = e.xy
    if e.kind in ("0", "1"):
        ax.text(x, y, e.label, fontsize=FONT_SIZES["junction"] * scale, fontweight="bold", color=color,
                ha="center", va="center", gid=f"element:{e.name}")
        (sx, sy), ha, va, _ = e.subscript
        ax.text(sx, sy, e.name, fontsize=FONT_SIZES["subscript"] * scale, color="0.3", ha=ha, va=va)
        return
    bbox = None
    if e.kind == "Eq":
        bbox = dict(boxstyle="round,pad=0.35", fc="white", ec=color, lw=0.9 * scale)
    ax.text(x, y, e.label, fontsize=FONT_SIZES["element"] * scale, color=color, ha="center", va="center_baseline",
            bbox=bbox, gid=f"element:{e.name}")


def _note_lines(geometry, width) -> int:
    return sum(len(textwrap.wrap(n, _wrap_width(width))) for n in geometry.notes)


def _wrap_width(width_in) -> int:
    return max(40, int(width_in * 72 / (0.55 * 8.0)))


def _legend_entries(geometry) -> list:
    entries = []
    if geometry.derivative:
        names = ", ".join(f"{e} (bond {b})" for e, b in geometry.derivative)
        entries.append(("red", f"derivative causality: {names}"))
    if geometry.arbitrary:
        entries.append(("darkorange", f"arbitrary causality (algebraic loop): {', '.join(geometry.arbitrary)}"))
    return entries


def _draw_notes(ax, geometry, title, scale):
    """Title, causality problems under it, and a legend for coloured strokes."""
    from matplotlib.lines import Line2D
    fig = ax.figure
    width = ax.get_position().width * fig.get_figwidth()
    note = "\n".join(line for n in geometry.notes for line in textwrap.wrap(n, _wrap_width(width)))
    note_pts = (note.count("\n") + 1) * 8.0 * scale * 1.25 + 4 if note else 0.0
    if title:
        ax.set_title(title, fontsize=11 * max(scale, 0.75), pad=4 + note_pts)
    if note:
        ax.annotate(note, (0.5, 1.0), xycoords="axes fraction", xytext=(0, 3), textcoords="offset points",
                    ha="center", va="bottom", fontsize=8.0 * scale, color="firebrick", gid="causality-note")
    entries = _legend_entries(geometry)
    if entries:
        handles = [Line2D([], [], color=c, lw=2, label=text) for c, text in entries]
        ax.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, 0.0), frameon=False,
                  fontsize=7.5 * scale, handlelength=1.2)
