"""Drawing: files written, half-arrows and causal strokes where the conventions put them.

Expected stroke ends follow the causality rules of Karnopp, Margolis &
Rosenberg, *System Dynamics*, 5th ed., ch. 5: an effort source sets the
effort (stroke at the far end of its bond), an I in integral causality
receives effort (stroke at the I), a C in integral causality sets the
effort (stroke at the junction), a resistor on a 1-junction receives flow
and sets the effort (stroke at the junction).
"""
import math

import matplotlib
import pytest

from bondgraph import GY, TF, BondGraph, C, CField, EquationElement, I, MSf, One, R, Se, Zero
from bondgraph.draw import LAYOUTS, draw, draw_geometry
from plants.library import mass_spring_chain

matplotlib.use("Agg")


# -- graphs -------------------------------------------------------------------
def mass_spring_damper():
    g = BondGraph("msd")
    for e in (Se("F"), One("j"), I("m", 2.0), R("b", 0.5), C("k", stiffness=10.0)):
        g.add(e)
    g.connect("F", "j")
    g.connect("j", "m")
    g.connect("j", "b")
    g.connect("j", "k")
    return g


def dc_motor():
    """Se V -> 1 (La, Ra) -> GY km -> 1 (Jm, bm) -> TF n -> 1 (bL)."""
    g = BondGraph("dc_motor")
    for e in (Se("V"), One("i_arm"), I("La", 1e-3), R("Ra", 1.0), GY("km", 0.05), One("w_motor"),
              I("Jm", 1e-4), R("bm", 1e-5), TF("n", 0.1), One("w_load"), R("bL", 2e-3)):
        g.add(e)
    for tail, head in (("V", "i_arm"), ("i_arm", "La"), ("i_arm", "Ra"), ("i_arm", "km"), ("km", "w_motor"),
                       ("w_motor", "Jm"), ("w_motor", "bm"), ("w_motor", "n"), ("n", "w_load"), ("w_load", "bL")):
        g.connect(tail, head)
    return g


def geared_inertias():
    """Two inertias rigidly geared: J2 is in derivative causality."""
    g = BondGraph("geared")
    for e in (Se("tau"), One("w1"), I("J1", 0.01), R("b", 0.05), TF("n", 0.2), One("w2"), I("J2", 0.5)):
        g.add(e)
    for tail, head in (("tau", "w1"), ("w1", "J1"), ("w1", "b"), ("w1", "n"), ("n", "w2")):
        g.connect(tail, head)
    g.connect("w2", "J2", name="b_J2")
    return g


def two_sources_on_a_zero_junction():
    g = BondGraph("conflict")
    for e in (Se("V1"), Se("V2"), Zero("node"), R("load", 1.0)):
        g.add(e)
    g.connect("V1", "node", name="a")
    g.connect("V2", "node", name="b")
    g.connect("node", "load", name="c")
    return g


def multiports():
    """Equation-defined chambers and a two-port C-field between two junctions."""
    g = BondGraph("multiports")
    for k in (1, 2):
        g.add_input(f"u{k}")
        g.add(MSf(f"valve{k}", f"u{k}*1e-3"))
        g.add(EquationElement(f"ch{k}", ports={"pn": "in", "mech": "out"},
                              outputs={"e_pn": f"P{k}", "e_mech": f"P{k}*Ap"},
                              states={f"P{k}": f"f_pn - P{k}*f_mech"}, params={"Ap": 1e-3}))
        g.add(One(f"v{k}"))
        g.connect(f"valve{k}", (f"ch{k}", "pn"))
        g.connect((f"ch{k}", "mech"), f"v{k}")
    g.add(CField("spring2", ["a", "b"], energy="q_a**2/2 + q_b**2/2 + q_a*q_b/4"))
    g.connect("v1", ("spring2", "a"))
    g.connect("v2", ("spring2", "b"))
    return g


GRAPHS = {"msd": mass_spring_damper, "dc_motor": dc_motor, "derivative": geared_inertias,
          "conflict": two_sources_on_a_zero_junction}


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    import matplotlib.pyplot as plt
    plt.close("all")


def stroke_artists(fig_or_ax):
    """Causal-stroke artists by bond name (draw() gives them the id ``stroke:<bond>``)."""
    ax = fig_or_ax.axes[0] if hasattr(fig_or_ax, "get_size_inches") else fig_or_ax
    return {a.get_gid().split(":", 1)[1]: a for a in ax.lines if a.get_gid().startswith("stroke:")}


def text_boxes(geometry):
    """Every text's box: element labels, junction names, bond names, port names."""
    boxes = [(f"element {e.name}", e.box) for e in geometry.elements.values()]
    boxes += [(f"junction name {e.name}", e.subscript[3]) for e in geometry.elements.values() if e.subscript]
    boxes += [(f"bond name {b.name}", b.label[3]) for b in geometry.bonds.values()]
    boxes += [(f"port {p[0]} of {b.name}", p[4]) for b in geometry.bonds.values() for p in b.ports]
    return boxes


def overlapping(boxes, tol=1e-3):
    """Pairs of overlapping boxes, except a junction's name with its own (padded) digit box."""
    return [(na, nb) for i, (na, a) in enumerate(boxes) for nb, b in boxes[i + 1:]
            if a[0] < b[2] - tol and b[0] < a[2] - tol and a[1] < b[3] - tol and b[1] < a[3] - tol
            and not (na.startswith("element ") and nb == f"junction name {na[8:]}")]


# -- files ------------------------------------------------------------------------
@pytest.mark.parametrize("name", GRAPHS)
def test_png_and_svg_are_written(tmp_path, name):
    g = GRAPHS[name]()
    png, svg = tmp_path / f"{name}.png", tmp_path / f"{name}.svg"
    fig = draw(g, png)
    draw(g, svg)
    assert png.stat().st_size > 5_000 and svg.stat().st_size > 5_000
    image = matplotlib.image.imread(png)
    width, height = fig.get_size_inches()
    assert image.shape[2] == 4  # RGBA, 150 dpi (Agg truncates the pixel count)
    assert abs(image.shape[0] - height * 150) < 1 and abs(image.shape[1] - width * 150) < 1
    assert image[..., :3].min() < 0.1  # something dark was drawn on the white page
    if name != "conflict":
        assert 'id="stroke:' in svg.read_text()


def test_pdf_and_graph_method(tmp_path):
    fig = mass_spring_damper().draw(tmp_path / "msd.pdf")
    assert (tmp_path / "msd.pdf").read_bytes().startswith(b"%PDF")
    assert len(stroke_artists(fig)) == 4


# -- geometry ---------------------------------------------------------------------
def test_one_stroke_per_bond_at_the_textbook_end():
    g = mass_spring_damper()
    fig = draw(g)
    strokes = stroke_artists(fig)
    assert sorted(strokes) == sorted(g.bonds)
    geometry = draw_geometry(g)
    expected = {"bond1": "head",   # Se F sets the effort: stroke at the junction
                "bond2": "head",   # integral I m receives the effort: stroke at the I
                "bond3": "tail",   # R b receives flow, sets effort: stroke at the junction
                "bond4": "tail"}   # integral C k sets the effort: stroke at the junction
    for name, bond in geometry.bonds.items():
        assert bond.stroke_end == expected[name] == g.causality().stroke_end(g.bonds[name])
        end = bond.end if bond.stroke_end == "head" else bond.start
        (x0, y0), (x1, y1) = bond.stroke
        assert math.isclose((x0 + x1) / 2, end[0], abs_tol=1e-9) and math.isclose((y0 + y1) / 2, end[1], abs_tol=1e-9)
        d = (bond.end[0] - bond.start[0], bond.end[1] - bond.start[1])
        assert abs(d[0] * (x1 - x0) + d[1] * (y1 - y0)) < 1e-9 * math.hypot(*d)  # perpendicular to the bond
        receiver = bond.head if bond.stroke_end == "head" else bond.tail
        centre = geometry.elements[receiver].xy
        other = geometry.elements[bond.tail if receiver == bond.head else bond.head].xy
        assert math.dist(end, centre) < math.dist(end, other)  # next to the element receiving the effort
        xs, ys = strokes[name].get_data()  # the artist is where the geometry says
        assert (xs[0], ys[0], xs[1], ys[1]) == pytest.approx((x0, y0, x1, y1))


@pytest.mark.parametrize("name", ["msd", "dc_motor", "derivative"])
def test_half_arrow_at_the_head_on_the_left(name):
    for bond in draw_geometry(GRAPHS[name]()).bonds.values():
        (tx, ty), (bx, by) = bond.barb
        assert (tx, ty) == bond.end
        d = (bond.end[0] - bond.start[0], bond.end[1] - bond.start[1])
        barb = (bx - tx, by - ty)
        assert d[0] * barb[1] - d[1] * barb[0] > 0  # left of the power direction
        assert d[0] * barb[0] + d[1] * barb[1] < 0  # pointing back along the bond
        assert bond.side == "left"


def test_dc_motor_reads_left_to_right():
    geometry = draw_geometry(dc_motor())
    x = {n: e.xy[0] for n, e in geometry.elements.items()}
    y = {n: e.xy[1] for n, e in geometry.elements.items()}
    chain = ["V", "i_arm", "km", "w_motor", "n", "w_load"]
    assert all(x[a] < x[b] for a, b in zip(chain, chain[1:]))
    assert len({round(y[n], 9) for n in chain}) == 1  # the power path is one straight line
    assert y["La"] != y["i_arm"] and y["Ra"] != y["i_arm"] and x["La"] == x["i_arm"]  # hung above/below


@pytest.mark.parametrize("build", [*GRAPHS.values(), multiports, lambda: mass_spring_chain(10)])
def test_no_text_overlaps_and_bonds_clear_other_labels(build):
    g = build()
    geometry = draw_geometry(g)
    assert overlapping(text_boxes(geometry)) == []
    for e in geometry.elements.values():
        if e.subscript:  # a junction's name sits beside its digit: off its centre, within 0.25 in
            x0, y0, x1, y1 = e.subscript[3]
            assert not (x0 < e.xy[0] < x1 and y0 < e.xy[1] < y1)
            assert max(abs(x0 - e.xy[0]), abs(x1 - e.xy[0])) < 1.0 and min(abs(y0 - e.xy[1]), abs(y1 - e.xy[1])) < 0.25
    for bond in geometry.bonds.values():
        for t in (0.1 * k for k in range(11)):
            p = (bond.start[0] + t * (bond.end[0] - bond.start[0]), bond.start[1] + t * (bond.end[1] - bond.start[1]))
            inside = [e.name for e in geometry.elements.values()
                      if e.box[0] + 1e-6 < p[0] < e.box[2] - 1e-6 and e.box[1] + 1e-6 < p[1] < e.box[3] - 1e-6]
            assert inside == [], f"bond {bond.name} crosses the label of {inside}"


def test_derivative_causality_is_marked():
    g = geared_inertias()
    geometry = draw_geometry(g)
    assert geometry.derivative == (("J2", "b_J2"),)
    assert geometry.bonds["b_J2"].status == "derivative" and geometry.elements["J2"].status == "derivative"
    fig = draw(g)
    strokes = stroke_artists(fig)
    assert len(strokes) == len(g.bonds)
    assert matplotlib.colors.same_color(strokes["b_J2"].get_color(), "red")
    assert all(matplotlib.colors.same_color(a.get_color(), "black") for n, a in strokes.items() if n != "b_J2")
    legend = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert legend == ["derivative causality: J2 (bond b_J2)"]


def test_causal_conflict_is_drawn_not_raised(tmp_path):
    g = two_sources_on_a_zero_junction()
    fig = draw(g, tmp_path / "conflict.png")
    assert stroke_artists(fig) == {}
    assert sum(a.get_gid().startswith("barb:") for a in fig.axes[0].lines) == 3  # power still shown
    note = next(t for t in fig.axes[0].texts if t.get_gid() == "causality-note").get_text()
    assert "V2" in note and "node" in note and "bond b" in note
    geometry = draw_geometry(g)
    assert {geometry.elements[n].status for n in ("V2", "node")} == {"conflict"}
    assert all(b.stroke is None for b in geometry.bonds.values())


def test_without_causality_no_strokes():
    fig = draw(dc_motor(), causality=False)
    assert stroke_artists(fig) == {}


def test_multiport_port_names_are_written():
    geometry = draw_geometry(multiports())
    ports = sorted(p[0] for b in geometry.bonds.values() for p in b.ports)
    assert ports == ["a", "b", "mech", "mech", "pn", "pn"]
    assert geometry.elements["ch1"].label == "ch1" and geometry.elements["spring2"].label == "C:spring2"


@pytest.mark.parametrize("layout", LAYOUTS)
def test_every_layout_draws(layout):
    g = dc_motor()
    geometry = draw_geometry(g, layout=layout)
    assert set(geometry.elements) == set(g.elements) and set(geometry.bonds) == set(g.bonds)
    assert all(math.isfinite(v) for e in geometry.elements.values() for v in e.xy)


def test_fifty_elements_fit_a_readable_figure(tmp_path):
    g = mass_spring_chain(10)
    assert len(g.elements) == 51
    fig = draw(g, tmp_path / "chain.png")
    width, height = fig.get_size_inches()
    assert 10 < width <= 40 and height <= 30
    assert len(stroke_artists(fig)) == len(g.bonds)


def test_draws_into_given_axes():
    import matplotlib.pyplot as plt
    fig, (left, right) = plt.subplots(1, 2, figsize=(10, 4))
    assert draw(dc_motor(), ax=right, title="motor") is fig
    assert right.get_title() == "motor" and not left.lines
    assert len(stroke_artists(right)) == 10


# -- bad input --------------------------------------------------------------------
def test_bad_options_are_named(tmp_path):
    g = mass_spring_damper()
    with pytest.raises(ValueError, match="unknown layout 'dot'.*auto, layered"):
        draw(g, layout="dot")
    with pytest.raises(ValueError, match=r"'msd.jpg'.*\.png, \.svg, \.pdf"):
        draw(g, tmp_path / "msd.jpg")
    with pytest.raises(TypeError, match="colour"):
        g.draw(tmp_path / "msd.png", colour="red")
    assert not list(tmp_path.iterdir())
