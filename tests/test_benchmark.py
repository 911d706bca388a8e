"""The generalisation benchmark's machinery: truth plants, effects, case drawing, scoring.

The truth plants are hand-written state equations; here they are checked
against the library's bond graphs (``bondgraph.numerics.simulate``), and the effects
against closed forms.  One small seeded run diagnoses two cases end to end.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import plants.library as library
from bondgraph.numerics import simulate
from diagnosis.benchmark import plants_textbook as tb
from diagnosis.benchmark.draw import (KINDS_BEFORE_32, KINDS_BEFORE_34, KINDS_BEFORE_35, KINDS_BEFORE_36, RATIOS,
                                      CaseSpec, draw_cases, realise)
from diagnosis.benchmark.effects import KIND_PLACES, make_effect, places_for
from diagnosis.benchmark.plants import FAST, PLANTS, PLANTS_BEFORE_34
from diagnosis.benchmark.report import markdown, summarise
from diagnosis.benchmark.run import run_case
from diagnosis.benchmark.simulate import simulate_truth
from diagnosis.errors import BenchmarkError

TEXTBOOK = [tb.mass_spring_damper, tb.dc_motor, tb.rlc, tb.coupled_tanks, tb.geared_inertias]


def _levels(plant, seconds, seed=3):
    n = int(round(seconds * plant.rate)) + 1
    t = np.arange(n) / plant.rate
    rng = np.random.default_rng(seed)
    u = {}
    for spec in plant.inputs:
        held = rng.uniform(spec.low, spec.high, size=n // 7 + 2)
        u[spec.name] = np.repeat(held, 7)[:n]
    return t, u


@pytest.mark.parametrize("factory", TEXTBOOK, ids=lambda f: f.__name__)
def test_textbook_truth_equals_library_graph(factory):
    plant = factory()
    t, u = _levels(plant, min(plant.duration, 3.0))
    truth = simulate_truth(plant, t, u)
    # LSODA (given the compiled Jacobian, it turns to BDF on a stiff stretch): "auto" takes Radau for
    # the DC motor, whose restart at each of the 430 held levels cost 22 s here, LSODA 3 s
    ref = simulate(library.build(plant.model), (0.0, float(t[-1])), inputs={k: (t, v) for k, v in u.items()},
                   output_interval=float(t[1] - t[0]), x0=plant.nominal_x0, method="LSODA")
    # the tanks start at rest: in 3 s the lower level moves 0.1 mm, less than its scale
    floor = {"h1": 1e-3, "h2": 1e-3, "Q_out": 1e-6} if plant.name == "tanks" else {}
    for o in plant.outputs:
        y, r = truth[o.name], np.asarray(ref[o.name])
        assert np.max(np.abs(y - r)) <= 1e-4 * max(np.std(r), floor.get(o.name, 0.0)) + 1e-12, o.name


def test_a_sharp_friction_is_resolved_in_the_truth_as_in_the_library_graph():
    """A brush drop of 0.67 V sharp at 7.7 mA on the DC motor's armature: its slope at rest makes the
    plant too stiff for the truth's 8 RK4 sub-steps per millisecond, where the current chattered
    about zero (4.7 % of its spread away from the physics; seed 1212, case 036).  The truth
    integrates it with LSODA and equals the library graph with the catalogue's Coulomb friction at
    the same values."""
    from diagnosis.catalogue import candidates
    from diagnosis.place import Place
    plant = tb.dc_motor()
    t, u = _levels(plant, 0.2)
    effect = make_effect("coulomb_friction", plant, "junction", "i_arm", 0.6675, {}, {"eps": 0.0077, "sign": -1.0})
    truth = simulate_truth(plant, t, u, effect)
    graph = library.build(plant.model)
    (cand,) = [c for c in candidates(graph, Place("junction", "i_arm")) if c.kind == "coulomb_friction"]
    ref = simulate(cand.build(graph, {cand.params[0].name: 0.6675, cand.params[1].name: 0.0077}), (0.0, float(t[-1])),
                   inputs={k: (t, v) for k, v in u.items()}, output_interval=float(t[1] - t[0]), x0=plant.nominal_x0,
                   method="Radau", rtol=1e-10, atol=1e-12)
    for o in plant.outputs:
        y, r = truth[o.name], np.asarray(ref[o.name])
        assert np.max(np.abs(y - r)) <= 1e-4 * np.std(r), o.name


@pytest.mark.parametrize("side", [1.0, -1.0])
def test_a_damping_harder_one_way_in_the_truth_equals_the_catalogues_law(side):
    """The truth's asymmetric viscous friction (m on the drawn side of the flow, rho m on the other)
    equals the library graph with the catalogue's law at b_fwd, b_back = m, rho m (or swapped):
    the truth's flow at a junction has the graph's sign."""
    from diagnosis.catalogue import candidates
    from diagnosis.place import Place
    plant = tb.mass_spring_damper()
    t, u = _levels(plant, 3.0)
    effect = make_effect("asymmetric_viscous_friction", plant, "junction", "v_mass", 0.6, {},
                         {"sign": side, "rho": 0.2, "eps": 1e-3})
    truth = simulate_truth(plant, t, u, effect)
    graph = library.build(plant.model)
    (cand,) = [c for c in candidates(graph, Place("junction", "v_mass")) if c.kind == "asymmetric_viscous_friction"]
    values = dict(zip([p.name for p in cand.params], (0.6, 0.12) if side > 0 else (0.12, 0.6)))
    ref = simulate(cand.build(graph, values), (0.0, float(t[-1])), inputs={k: (t, v) for k, v in u.items()},
                   output_interval=float(t[1] - t[0]), x0=plant.nominal_x0, method="LSODA")
    for o in plant.outputs:
        y, r = truth[o.name], np.asarray(ref[o.name])
        assert np.max(np.abs(y - r)) <= 1e-4 * np.std(r), o.name


def test_a_quadratic_drag_in_the_truth_equals_the_catalogues_law():
    """The truth's drag m v |v| equals the library graph with the catalogue's quadratic drag at c_d = m."""
    from diagnosis.catalogue import candidates
    from diagnosis.place import Place
    plant = tb.mass_spring_damper()
    t, u = _levels(plant, 3.0)
    truth = simulate_truth(plant, t, u, make_effect("quadratic_drag", plant, "junction", "v_mass", 0.7, {},
                                                    {"sign": 1.0, "eps": 1e-3}))
    graph = library.build(plant.model)
    (cand,) = [c for c in candidates(graph, Place("junction", "v_mass")) if c.kind == "quadratic_drag"]
    ref = simulate(cand.build(graph, {cand.params[0].name: 0.7}), (0.0, float(t[-1])),
                   inputs={k: (t, v) for k, v in u.items()}, output_interval=float(t[1] - t[0]),
                   x0=plant.nominal_x0, method="LSODA")
    for o in plant.outputs:
        y, r = truth[o.name], np.asarray(ref[o.name])
        assert np.max(np.abs(y - r)) <= 1e-4 * np.std(r), o.name


def test_constant_load_on_msd_gives_the_static_deflection():
    # F = 0, a constant 0.3 N at the mass: x settles at 0.3 / k = 0.075 m (k = 4 N/m)
    plant = tb.mass_spring_damper()
    t = np.arange(0, 60.0, 1 / plant.rate)
    eff = make_effect("constant_load", plant, "junction", "v_mass", 0.3, {}, {"sign": 1.0})
    y = simulate_truth(plant, t, {"F": np.zeros(t.size)}, eff)
    assert y["x"][-1] == pytest.approx(0.075, rel=1e-4)


def test_leak_on_the_lower_tank_holds_the_analytic_steady_levels():
    # Q_in = Q_out + k p2 at steady state, Q_out = a2 sqrt(2 g h2), p2 = rho g h2: a quadratic in
    # sqrt(h2); the upper tank passes Q_in through the orifice, h1 - h2 = (Q_in / a12)^2 / (2 g).
    # Started there, the truth stays there only if its leak takes k p2 from the lower tank
    plant = tb.coupled_tanks()
    q, k, a12, a2, g, rho, area = 2e-4, 2e-9, 5e-5, 4e-5, 9.81, 1000.0, 0.02
    root = max(np.roots([k * rho * g, a2 * np.sqrt(2 * g), -q]))
    h2 = root ** 2
    h1 = h2 + (q / a12) ** 2 / (2 * g)
    t = np.arange(0, 100.0, 1 / plant.rate)
    eff = make_effect("leak", plant, "junction", "P2", k, {}, {})
    y = simulate_truth(plant, t, {"Q_in": np.full(t.size, q)}, eff, x0=np.array([area * h1, area * h2]))
    assert np.ptp(y["h1"]) < 1e-9 * h1 and np.ptp(y["h2"]) < 1e-9 * h2
    # and without the leak the lower tank fills: its outflow alone takes less than Q_in there
    y = simulate_truth(plant, t, {"Q_in": np.full(t.size, q)}, x0=np.array([area * h1, area * h2]))
    assert y["h2"][-1] > h2 * (1 + 1e-3)


def test_a_viscous_friction_in_series_with_the_tanks_orifice_holds_its_steady_levels():
    # in series with the orifice: rho g (h1 - h2) = rho/2 (q / a12)^2 + b q at the steady flow q,
    # whose lower level is Q_out's, h2 = (q / a2)^2 / (2 g).  Started there, the truth stays there
    # only if it solves the orifice's flow together with the friction's pressure drop
    plant = tb.coupled_tanks()
    q, b, a12, a2, g, rho, area = 2e-4, 2e7, 5e-5, 4e-5, 9.81, 1000.0, 0.02
    h2 = (q / a2) ** 2 / (2 * g)
    h1 = h2 + ((q / a12) ** 2 / 2 + b * q / rho) / g
    t = np.arange(0, 100.0, 1 / plant.rate)
    eff = make_effect("viscous_friction", plant, "junction", "Q12", b, {}, {"eps": 1e-6, "sign": 1.0})
    y = simulate_truth(plant, t, {"Q_in": np.full(t.size, q)}, eff, x0=np.array([area * h1, area * h2]),
                       signals=True)
    assert np.ptp(y["h1"]) < 1e-9 * h1 and np.ptp(y["h2"]) < 1e-9 * h2
    assert y["_signals"]["Q12"] == pytest.approx(np.full(t.size, q), rel=1e-9)


def test_sensor_and_delay_effects_are_exact():
    plant = tb.mass_spring_damper()
    t, u = _levels(plant, 5.0)
    base = simulate_truth(plant, t, u)
    off = simulate_truth(plant, t, u, make_effect("sensor_offset", plant, "output", "x", 0.02, {}, {}))
    gain = simulate_truth(plant, t, u, make_effect("sensor_gain", plant, "output", "v", 0.1, {}, {}))
    np.testing.assert_allclose(off["x"], base["x"] + 0.02, atol=1e-15)
    np.testing.assert_allclose(gain["v"], 1.1 * base["v"], rtol=1e-14)
    delay = simulate_truth(plant, t, u, make_effect("transport_delay", plant, "input", "F", 0.2, {}, {}))
    shifted = simulate_truth(plant, t, {"F": np.concatenate([np.full(10, u["F"][0]), u["F"][:-10]])})
    np.testing.assert_allclose(delay["x"], shifted["x"], atol=1e-14)


def test_every_kind_has_a_place_on_some_plant():
    plants = [f() for f in PLANTS.values()]
    missing = [k for k in KIND_PLACES if not any(places_for(p, k) for p in plants)
               and k not in ("pressure_dependent_friction",)]
    assert missing == []


def test_draw_is_reproducible_and_balanced():
    specs = draw_cases(80, 11, PLANTS)
    assert [s.label for s in specs] == [s.label for s in draw_cases(80, 11, PLANTS)]
    nulls = sum(s.kind == "none" for s in specs)
    assert nulls / len(specs) >= 0.15
    assert all(s.kind == "none" or 3.0 <= s.ratio <= 30.0 for s in specs)
    kinds = {s.kind for s in specs}
    assert len(kinds) >= 10
    drifting = [s for s in specs if PLANTS[s.plant]().drifts and s.kind != "none"]
    if any(f().drifts for f in PLANTS.values()):
        assert len(drifting) >= 10


def test_the_drawn_kinds_can_be_chosen_and_the_earlier_vocabulary_replayed():
    """Every kind is drawn by default; ``kinds`` restricts the draw, and the kinds drawn until
    session 31 give a seed's cases as they were drawn then (the new kind changed the shuffles)."""
    assert {"asymmetric_viscous_friction", "quadratic_drag"} <= {s.kind for s in draw_cases(80, 11, PLANTS)}
    pair = ("viscous_friction", "asymmetric_viscous_friction")
    assert {s.kind for s in draw_cases(24, 11, FAST, pair)} == {"none", *pair}
    assert (draw_cases(80, 3434, PLANTS_BEFORE_34, KINDS_BEFORE_32)[4].label
            == "004-hydraulic-viscous_friction@junction:q_pipe")
    # session 34's sensor lag, radiation and heater pair joined: until then seed 3434's case 001
    # was a delay, now a lag; the plants and kinds of before draw it as it was
    assert {"sensor_lag", "radiation"} <= {s.kind for s in draw_cases(80, 11, PLANTS)}
    assert "heater-pair" in {s.plant for s in draw_cases(80, 11, PLANTS)}
    assert draw_cases(80, 3434, PLANTS_BEFORE_34, KINDS_BEFORE_34)[1].label == "001-msd-transport_delay@input:F"
    assert draw_cases(80, 3434, PLANTS, KINDS_BEFORE_35)[1].label == "001-msd-valve_lag@input:F"
    # session 35's input offset and gain and relaxation joined: the case is now a relaxing branch
    assert {"input_offset", "input_gain", "relaxation"} <= {s.kind for s in draw_cases(80, 11, PLANTS)}
    assert draw_cases(80, 3434, PLANTS, KINDS_BEFORE_36)[1].label == "001-msd-relaxation@junction:v_mass"
    # session 36's saturating inductor joined
    assert "inductor_saturation" in {s.kind for s in draw_cases(80, 11, PLANTS)}
    assert draw_cases(80, 3434, PLANTS)[1].label == "001-drivetrain-coulomb_friction@junction:dw_shaft"
    with pytest.raises(BenchmarkError, match="unknown effect kind.*'?friction_typo"):
        draw_cases(4, 11, FAST, ("friction_typo",))


def test_realised_effect_has_the_drawn_size():
    spec = CaseSpec(0, 5, "msd", "coulomb_friction", "junction", "v_mass", target_change=0.1, ratio=10.0)
    rec = realise(spec, tb.mass_spring_damper())
    assert rec.change == pytest.approx(0.1, rel=0.3)
    d = rec.truth[rec.affected] - rec.nominal[rec.affected]
    assert np.sqrt(np.mean(d ** 2)) / rec.sigma[rec.affected] == pytest.approx(10.0, rel=1e-9)


def test_the_truths_sign_sharpness_is_drawn_per_case():
    """tanh(v/eps) with eps/v_rms log-uniform in draw.SHARPNESS, from the case's own stream: the
    catalogue's fixed smoothing is not the truth's."""
    from diagnosis.benchmark import draw
    ratios = []
    for seed in (5, 6, 7, 8):
        spec = CaseSpec(0, seed, "msd", "coulomb_friction", "junction", "v_mass", target_change=0.1, ratio=10.0)
        rec = realise(spec, tb.mass_spring_damper())
        v_rms = np.sqrt(np.mean(rec.nominal["_signals"]["v_mass"] ** 2))
        ratios.append(rec.effect.shape["eps"] / v_rms)
    assert all(draw.SHARPNESS[0] <= r <= draw.SHARPNESS[1] for r in ratios)
    assert max(ratios) / min(ratios) > 1.5


def test_summary_counts():
    base = dict(seconds_diagnose=1.0, place_ok=True, answer_place="", plant="msd")
    results = [dict(base, label="a", kind="coulomb_friction", answer_kind="coulomb_friction", kind_ok=True,
                    improvement=0.9),
               dict(base, label="b", kind="leak", answer_kind="none", kind_ok=False, place_ok=False,
                    improvement=0.0, judge="segments"),
               dict(base, label="c", kind="none", answer_kind="none", kind_ok=True, improvement=float("nan")),
               dict(base, label="d", kind="none", answer_kind="leak", kind_ok=False, improvement=float("nan"))]
    s = summarise(results)
    h = s["headline"]
    assert (h["kind_right"], h["place_right"], h["holdout_halved"], h["false_alarms"]) == (0.5, 0.5, 0.5, 0.5)
    assert s["confusion"]["leak"]["none"] == 1 and s["confusion"]["none"]["leak"] == 1
    assert h["segment_judged"] == 1 and "1 judged by the segment simulation error" in markdown(s, seed=0)
    assert "| leak | 1 | 0 % |" in markdown(s, seed=0)


def test_a_detuned_value_read_as_another_effect_is_the_value_not_the_answer():
    """Under --detune, the first answered effect that lists a nominal_value at a junction bonded to
    the detuned element as not told apart from it is that value read another way, unless a value
    answer names the detuned value itself: it names the detuned value and leaves the scored answer;
    listed elsewhere, or beside the value answered, it stays the answer (seed 3739's case 012: an
    asymmetric viscous friction beside its spring's value refitted)."""
    from types import SimpleNamespace
    from diagnosis.benchmark.run import score_case
    spec = CaseSpec(0, 5, "msd", "sensor_offset", "output", "x", target_change=0.1, ratio=10.0)
    rec = SimpleNamespace(spec=spec, plant=SimpleNamespace(model="mass-spring-damper", drifts=False), change=0.1,
                          nominal_drifts=False, affected="x",
                          effect=SimpleNamespace(place="x", accepted_places=lambda: ["output x"],
                                                 equivalent_answers=set))
    detuned = {"element": "m", "parameter": "m", "nominal": 1.0, "factor": 0.874}
    gain = {"kind": "input_gain", "attached_to": "input F", "parameters": {"gain": 0.874},
            "indistinguishable": [{"kind": "nominal_value", "place": "junction v_mass"}]}
    offset = {"kind": "sensor_offset", "attached_to": "output x", "parameters": {"offset": 0.01}}
    answer = {"missing_physics": [gain, offset], "fit": {"nominal": {"x": 0.2}, "improved": {"x": 0.03}}}
    s = score_case(rec, answer, detuned)
    assert (s.answer_kind, s.answer_place, s.kind_ok, s.detuned_named) == ("sensor_offset", "output x", True, True)
    # beside a value answer that names the detuned value, the reading is an answer of its own
    value = {"kind": "nominal_value", "attached_to": "junction v_mass", "parameters": {"m": 0.874}}
    answer["missing_physics"] = [gain, value]
    s = score_case(rec, answer, detuned)
    assert (s.answer_kind, s.kind_ok, s.detuned_named) == ("input_gain", False, True)
    # nor beside a value answer that lists the detuned value as not told apart from its own (seed
    # 3739's case 011: a valve lag beside a geared inertia's value, the other inertia detuned)
    value["parameters"], value["indistinguishable"] = {"other": 1.0}, gain["indistinguishable"]
    s = score_case(rec, answer, detuned)
    assert (s.answer_kind, s.kind_ok, s.detuned_named) == ("input_gain", False, True)
    gain["indistinguishable"] = [{"kind": "nominal_value", "place": "junction elsewhere"}]
    answer["missing_physics"] = [gain, offset]
    s = score_case(rec, answer, detuned)
    assert (s.answer_kind, s.kind_ok, s.detuned_named) == ("input_gain", False, False)


def test_kind_right_or_indistinguishable_is_a_measure_apart_from_kind_right():
    """A concealed kind the answer lists as indistinguishable (diagnosis.alternatives) counts in the
    separate measure, never in kind right; case files scored before the measure are left out of it."""
    from types import SimpleNamespace
    from diagnosis.benchmark.run import score_case
    spec = CaseSpec(0, 5, "msd", "constant_load", "junction", "v_mass", target_change=0.1, ratio=10.0)
    rec = SimpleNamespace(spec=spec, plant=SimpleNamespace(model="mass-spring-damper", drifts=False), change=0.1,
                          nominal_drifts=False, affected="x",
                          effect=SimpleNamespace(place="v_mass", accepted_places=lambda: ["junction v_mass"],
                                                 equivalent_answers=set))
    answer = {"missing_physics": [{"kind": "coulomb_friction", "attached_to": "junction v_mass", "parameters": {},
                                   "indistinguishable": [{"kind": "constant_load", "place": "junction v_mass"}]}],
              "fit": {"nominal": {"x": 0.2}, "improved": {"x": 0.03}}}
    s = score_case(rec, answer)
    assert (s.kind_ok, s.kind_or_indistinguishable_ok, s.indistinguishable) == (False, True, ["constant_load"])
    answer["missing_physics"][0]["indistinguishable"] = []
    assert not score_case(rec, answer).kind_or_indistinguishable_ok
    base = dict(seconds_diagnose=1.0, place_ok=True, answer_place="", plant="msd", improvement=0.9)
    results = [dict(base, label="a", kind="constant_load", answer_kind="coulomb_friction", kind_ok=False,
                    kind_or_indistinguishable_ok=True),
               dict(base, label="b", kind="leak", answer_kind="leak", kind_ok=True, kind_or_indistinguishable_ok=True),
               dict(base, label="c", kind="backlash", answer_kind="hysteresis", kind_ok=False,
                    kind_or_indistinguishable_ok=False),
               dict(base, label="d", kind="leak", answer_kind="none", kind_ok=False)]     # an older case file
    h = summarise(results)["headline"]
    assert h["kind_right"] == 0.25 and h["kind_right_or_indistinguishable"] == pytest.approx(2 / 3)
    assert "| kind right or among the stated indistinguishable alternatives (effect cases) | 67 % | |" in markdown(
        summarise(results), seed=0)


def test_a_quarter_of_the_recordings_have_a_sensors_glitches(tmp_path):
    """Drawn from a stream of their own (the case and its noise stay), 1-3 single samples of one
    varying output, 15-60 noise standard deviations off, in about a quarter of the cases; the
    written column has them, and a case without keeps its noise exactly."""
    from diagnosis.benchmark.run import GLITCHY, glitches, write_csv
    specs = draw_cases(80, 5757, PLANTS, KINDS_BEFORE_36)
    drawn = [np.random.default_rng([s.seed, 11]).uniform() < GLITCHY for s in specs]
    assert 0.15 < np.mean(drawn) < 0.35
    spec = next(s for s, d in zip(specs, drawn) if d and s.plant == "msd")
    rec = realise(spec, PLANTS[spec.plant]())
    ((o, (samples, jumps)),) = glitches(rec).items()
    size = np.abs(jumps) / rec.sigma[o]
    assert 1 <= samples.size <= 3 and np.all((size >= 15) & (size <= 60))
    write_csv(rec, tmp_path / "g.csv", np.random.default_rng(1))
    rec.spec = replace(spec, seed=next(s.seed for s, d in zip(specs, drawn) if not d))   # same truth, no glitch
    assert glitches(rec) == {}
    write_csv(rec, tmp_path / "c.csv", np.random.default_rng(1))
    written, clean = (np.loadtxt(tmp_path / f, delimiter=",", skiprows=1) for f in ("g.csv", "c.csv"))
    column = 1 + len(rec.plant.inputs) + [p.name for p in rec.plant.outputs].index(o)
    moved = np.flatnonzero(written[:, column] != clean[:, column])
    assert moved.tolist() == samples.tolist()
    np.testing.assert_allclose(written[samples, column] - clean[samples, column], jumps,
                               atol=2 * rec.quantum[o] + 1e-12)


def test_two_seeded_cases_end_to_end(tmp_path):
    coulomb = CaseSpec(0, 21, "msd", "coulomb_friction", "junction", "v_mass", target_change=0.15, ratio=15.0)
    null = CaseSpec(1, 22, "msd", "none", noise_share=0.01)
    for spec, kind in ((coulomb, "coulomb_friction"), (null, "none")):
        r = run_case(spec, PLANTS, tmp_path, max_effects=1)
        assert r["answer_kind"] == kind, r
        assert r["kind_ok"] and r["place_ok"]
    assert r["improvement"] != r["improvement"]     # NaN on a null case


def test_a_lagging_position_sensor_is_found_at_its_time_constant(tmp_path):
    """A truth whose position sensor reads through a 0.1 s lag (its velocity sensor does not): the
    sensor lag at output x, its time constant within 3 %; an actuator lag on the force would lag the
    velocity too.  Before session 34 the vocabulary had no sensor dynamics."""
    spec = next(s for s in draw_cases(6, 3, {"msd": PLANTS["msd"]}, ("sensor_lag",)) if s.kind != "none")
    r = run_case(spec, PLANTS, tmp_path, max_effects=1)
    assert r["answers"] == ["sensor_lag @ output x"] and r["kind_ok"] and r["place_ok"], r
    assert r["parameters"]["tau_sensor_x"] == pytest.approx(r["effect"]["magnitude"], rel=0.03)
    assert r["improvement"] > 0.5


def test_the_benchmark_command_on_a_small_seeded_subset(tmp_path, capsys):
    """What CI runs of the benchmark: four msd cases (three effects, one null) end to end,
    with the report's files; the full run is ``python -m diagnosis.benchmark`` (80 cases)."""
    import json

    from diagnosis.benchmark.__main__ import main
    assert main(["--cases", "4", "--seed", "7", "--plants", "msd", "--report", str(tmp_path),
                 "--max-effects", "1"]) == 0
    results = json.loads((tmp_path / "results.json").read_text())
    head = results["summary"]["headline"]
    assert (head["scored"], head["null_cases"], head["generator_errors"]) == (4, 1, 0)
    assert head["false_alarms"] == 0.0
    assert (tmp_path / "results.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "| kind right (effect cases) |" in (tmp_path / "results.md").read_text()
    assert len(list((tmp_path / "cases").glob("*.json"))) == 4
    # a rerun finds every case done and diagnoses nothing again
    assert main(["--cases", "4", "--seed", "7", "--plants", "msd", "--report", str(tmp_path)]) == 0
    assert "4 cases (4 done before)" in capsys.readouterr().err


def test_a_detuned_nominal_is_scored_on_the_concealed_effect_and_the_value_named(tmp_path):
    """``--detune``: each nominal has one storage value a few per cent off, drawn per case (the
    truth keeps the library's); a null answered with that value alone is no false alarm."""
    import json

    from diagnosis.benchmark.__main__ import main
    from diagnosis.benchmark.detune import detuned_nominal
    graph, detuned = detuned_nominal("mass-spring-damper", 12345, 0.05)
    assert detuned == detuned_nominal("mass-spring-damper", 12345, 0.05)[1]       # the case's seed decides
    assert detuned["parameter"] in ("m", "k") and 0.025 <= abs(detuned["factor"] - 1) <= 0.05
    assert graph.parameters()[detuned["parameter"]].value == pytest.approx(detuned["nominal"] * detuned["factor"])
    assert detuned_nominal("mass-spring-damper", 12345, 0.0)[1] == {}
    # --detune-elements ICR: a linear R may be drawn too (here the damper, for some seeds)
    drawn = {detuned_nominal("mass-spring-damper", seed, 0.05, "ICR")[1]["parameter"] for seed in range(12)}
    assert drawn == {"m", "k", "b"}
    with pytest.raises(BenchmarkError, match="IC or ICR"):
        detuned_nominal("mass-spring-damper", 1, 0.05, "R")
    assert main(["--cases", "4", "--seed", "7", "--plants", "msd", "--only", "0,3", "--detune", "0.05",
                 "--kinds", "before-32", "--report", str(tmp_path)]) == 0
    results = json.loads((tmp_path / "results.json").read_text())
    cases = {r["kind"]: r for r in results["cases"]}
    null, effect = cases["none"], cases["coulomb_viscous_friction"]
    assert null["answers"] == ["nominal_value @ junction v_mass"] and null["kind_ok"] and null["detuned_named"]
    assert effect["kind_ok"] and effect["answer_kind"] == "coulomb_viscous_friction"
    assert "nominal_value @ junction v_mass" in effect["answers"] and effect["detuned_named"]
    head = results["summary"]["headline"]
    assert (head["detuned_cases"], head["detuned_named"], head["false_alarms"]) == (2, 1.0, 0.0)
    assert "| nominal detuned (2 cases, one storage value)" in (tmp_path / "results.md").read_text()


def test_sampling_scales_each_recordings_rate_and_length_and_is_reported(tmp_path):
    """``--sampling F``: a case is recorded at its plant's rate times a factor in [1/F, F] and for
    its duration times one in [1/sqrt F, sqrt F], drawn per case; the recording's time column
    carries it and the diagnosis is told nothing else."""
    import json

    from diagnosis.benchmark.__main__ import main
    from diagnosis.benchmark.sampling import resampled
    plant = PLANTS["msd"]()
    factors = [resampled(plant, seed, 2.0)[1] for seed in range(40)]
    assert all(0.5 <= d["rate_factor"] <= 2.0 and 2 ** -0.5 <= d["duration_factor"] <= 2 ** 0.5 for d in factors)
    assert min(d["rate_factor"] for d in factors) < 0.7 and max(d["rate_factor"] for d in factors) > 1.4
    assert resampled(plant, 3, 2.0)[1] == resampled(plant, 3, 2.0)[1]          # the case's seed decides
    assert resampled(plant, 3, 1.0) == (plant, {})
    with pytest.raises(BenchmarkError, match="at least 1"):
        resampled(plant, 3, 0.5)
    spec = draw_cases(4, 7, {"msd": PLANTS["msd"]})[1]
    scaled, drawn = resampled(plant, spec.seed, 2.0)
    rec = realise(spec, scaled)
    assert np.diff(rec.t) == pytest.approx(1.0 / (plant.rate * drawn["rate_factor"]))
    assert rec.t[-1] == pytest.approx(plant.duration * drawn["duration_factor"], abs=1.0 / scaled.rate)
    assert main(["--cases", "4", "--seed", "7", "--plants", "msd", "--only", "1", "--sampling", "2",
                 "--max-effects", "1", "--report", str(tmp_path)]) == 0
    results = json.loads((tmp_path / "results.json").read_text())
    case = results["cases"][0]
    assert case["sampling"]["rate"] == pytest.approx(scaled.rate)
    t = np.loadtxt(next((tmp_path / "recordings").glob("*.csv")), delimiter=",", skiprows=1, usecols=0)
    assert np.median(np.diff(t)) == pytest.approx(1.0 / scaled.rate, rel=1e-3)
    assert results["summary"]["headline"]["resampled_cases"] == 1
    assert "| recorded at another rate and length (1 cases)" in (tmp_path / "results.md").read_text()


def test_a_clipping_sensor_is_located_and_named(tmp_path):
    # the output place's correction has hinges at quantiles of the simulated output (a range),
    # and a limit the training part gives no evidence for is released, not left where it ends
    spec = CaseSpec(0, 72, "msd", "saturation", "output", "x", target_change=0.1, ratio=10.0)
    r = run_case(spec, PLANTS, tmp_path, max_effects=1)
    assert (r["answer_kind"], r["answer_place"]) == ("saturation", "output x"), r["answers"]
    assert r["improvement"] >= 0.5


def test_a_friction_the_segment_floor_hides_is_judged_open_loop(tmp_path):
    """Seed 4747, case 014: a viscous friction on the force-driven carriage, whose nominal drifts
    (segment judge). The fit recovers the truth's coefficient, but its segment error of the speed
    stays within the segment floor; simulated open-loop it predicts the held-out part to the
    noise, and it is named (diagnosis.open_loop_judge)."""
    spec = CaseSpec(14, 1019124, "carriage", "viscous_friction", "junction", "v_cart",
                    target_change=0.06575332060637167, ratio=3.0394915233352426, excitation="levels+sine")
    r = run_case(spec, PLANTS, tmp_path, max_effects=1)
    assert r["judge"] == "segments"
    assert (r["answer_kind"], r["answer_place"]) == ("viscous_friction", "junction v_cart"), r["answers"]
    truth = r["effect"]["magnitude"]
    assert r["parameters"]["b_visc_v_cart"] == pytest.approx(truth, rel=0.01)


def test_a_sensor_range_only_the_training_part_reaches_is_judged_there_under_the_segment_judge(tmp_path):
    """Seed 3535, case 014: the drifting carriage's position sensor reads nothing above -2.13 m,
    which only the training part reaches; the segment predictions of the held-out part are the
    nominal's, so the training part judges (diagnosis.training_judge), as under the open-loop judge."""
    spec = CaseSpec(14, 361030412, "carriage", "saturation", "output", "x", target_change=0.25694204126778714,
                    ratio=21.468635979323174, excitation="levels")
    r = run_case(spec, PLANTS, tmp_path, max_effects=1)
    assert r["judge"] == "segments"
    assert (r["answer_kind"], r["answer_place"]) == ("saturation", "output x"), r["answers"]
    lo, hi = r["effect"]["shape"]["lo"], r["effect"]["shape"]["hi"]
    top = 0.5 * (lo + hi) + r["effect"]["magnitude"] * 0.5 * (hi - lo)
    assert r["parameters"]["y_max_x"] == pytest.approx(top, abs=0.01)


def test_an_input_saturation_is_not_read_as_a_slow_lag_restarted_by_the_segment_judge(tmp_path):
    """Seed 4747, case 077: the drifting carriage's force is clipped above -1.5 N.  The segment
    judge fitted a 3.5 s valve lag's state afresh at every restart, a free force per segment, and
    the lag beat the saturation held out though its training error was 300 times larger.  The lag's
    state now follows the command through the restarts (diagnosis.segments.input_driven_states)."""
    spec = CaseSpec(77, 731321742, "carriage", "saturation", "input", "F", target_change=0.04188253229965152,
                    ratio=3.7941010592527395, excitation="prbs")
    r = run_case(spec, PLANTS, tmp_path, max_effects=1)
    assert r["judge"] == "segments"
    assert (r["answer_kind"], r["answer_place"]) == ("saturation", "input F"), r["answers"]
    assert r["improvement"] >= 0.5


def test_a_muscles_force_law_is_a_door_of_the_pam_truth():
    """Hysteresis may sit at a muscle's force law (the diagnosis's ``law muscle<i>``): only
    hysteresis draws there, so other kinds' draws are unchanged; its place is accepted at the
    seesaw and the other muscle, which differ from it by the lever arm r cos(psi) alone."""
    from diagnosis.benchmark.plants_pam import PAM_PARAMS, pam_frictionless

    plant = pam_frictionless()
    assert places_for(plant, "hysteresis") == [("junction", "seesaw"), ("junction", "muscle1"),
                                               ("junction", "muscle2")]
    assert places_for(plant, "coulomb_friction") == [("junction", "seesaw")]
    t = np.arange(0.0, 1.0, 1e-3)
    a = 1.5 * np.sin(2 * np.pi * 1.3 * t)
    u = {"u1": 5.0 + a, "u2": 5.0 - a}
    scales = {"rms": {"muscle1": 0.01, "seesaw": 0.3}}
    law = make_effect("hysteresis", plant, "junction", "muscle1", 2.0, scales, {"sigma": 1000.0, "eps": 1e-4})
    assert law.place == "law muscle1"
    assert law.accepted_places() == {"law muscle1", "law muscle2", "junction seesaw"}
    # a muscle's contraction rate is r cos(psi) times the joint's: at psi = 0 a friction force F
    # on muscle 1's law is a torque r F on the seesaw, and the two truths agree to cos(psi)
    r = PAM_PARAMS["r"]
    x = np.array([0.0, 0.2, 4e5, 4e5])
    sig = plant.signals(x, {})
    assert sig["muscle1"] == pytest.approx(r * 0.2) and sig["muscle2"] == pytest.approx(-r * 0.2)
    force = {"muscle1": 1.5}
    torque = plant.rhs(x, {"u1": 5.0, "u2": 5.0}, {"seesaw": r * 1.5})[1]
    assert plant.rhs(x, {"u1": 5.0, "u2": 5.0}, force)[1] == pytest.approx(torque, rel=1e-12)
    law_run = simulate_truth(plant, t, u, law)["psi"]
    nominal = simulate_truth(plant, t, u)["psi"]
    assert np.max(np.abs(law_run - nominal)) > 0.05          # deg: the braid friction shows


def test_a_stiff_effect_on_the_pam_truth_keeps_its_friction_held_per_quarter_millisecond():
    """A sharp friction at the seesaw makes the pam truth stiffer than its 4 sub-steps per sample
    resolve: finer RK4 steps nest inside them, and the Kikuuwe friction (Z = h / J) stays held
    over 0.25 ms, the plant's discrete law, not over the finer steps (seed 3535, case 019)."""
    from dataclasses import replace
    plant = PLANTS["pam"]()
    calls = []

    def counted(x, u, extra, h):
        calls.append(h)
        return plant.hold(x, u, extra, h)

    counting = replace(plant, hold=counted)
    t = np.arange(0.0, 0.02, 1.0 / plant.rate)
    u = {i.name: np.full(t.size, 0.5 * (i.low + i.high)) for i in plant.inputs}
    sharp = make_effect("coulomb_friction", plant, "junction", "seesaw", 0.01, {}, {"eps": 1e-4, "sign": 1.0})
    out = simulate_truth(counting, t, u, sharp)
    assert out["_finite"]
    during = calls[1:]          # the first call sizes the steps at the start state
    assert len(during) == (t.size - 1) * plant.substeps
    assert np.allclose(during, 1.0 / plant.rate / plant.substeps, rtol=1e-12)


def test_an_output_the_case_leaves_constant_is_not_bound(tmp_path):
    """Seed 2727, case 021: the pneumatic cylinder's load cell reads one value throughout (its
    pressure held, a null case): a user binds only what varies, and the diagnosis, which refuses a
    constant output, runs on the rest."""
    spec = CaseSpec(21, 1535409183, "pneumatic-cylinder", "none", "", "", target_change=0.0, ratio=0.0,
                    excitation="prbs", noise_share=0.0137447782733697)
    r = run_case(spec, PLANTS, tmp_path)
    assert r["error"] == "" and r["answer_kind"] == "none" and r["kind_ok"]


def test_an_lsoda_truth_that_crawls_counts_as_a_failed_run(monkeypatch):
    """A sample that takes more right-hand-side evaluations than the budget ends the run as
    non-finite (the calibration then tries a smaller effect) instead of running for hours."""
    import diagnosis.benchmark.simulate as simulate

    plant = PLANTS["exoskeleton"]()
    assert plant.method == "lsoda"
    t = np.arange(0.0, 0.2, 1.0 / plant.rate)
    u = {i.name: np.full(t.size, 0.5 * (i.low + i.high)) for i in plant.inputs}
    assert simulate_truth(plant, t, u)["_finite"]
    monkeypatch.setattr(simulate, "MAX_EVALS_PER_SAMPLE", 3)
    out = simulate_truth(plant, t, u)
    assert not out["_finite"] and np.isnan(next(iter(v for k, v in out.items() if not k.startswith("_")))[-1])


def test_an_effect_that_cannot_be_sized_is_a_generator_error(monkeypatch, tmp_path):
    """A truth that runs only far below the drawn size is not the drawn case: reported as a
    generator error, not scored as a miss or a hit."""
    import diagnosis.benchmark.draw as draw

    spec = CaseSpec(0, 5, "msd", "viscous_friction", "junction", "v_mass", target_change=0.1, ratio=10.0)
    monkeypatch.setattr(draw, "SIZE_TOLERANCE", 1.0001)       # no realised size is close enough
    out = run_case(spec, PLANTS, tmp_path)
    assert "could not be sized" in out["generator_error"]


def test_a_report_of_generator_errors_only_is_written(tmp_path):
    """A run whose every case is a generator error (``--only`` one such case) still writes its
    table and plot: no case scored, no confusion matrix (its plot took an empty matrix and raised)."""
    from diagnosis.benchmark.report import write_report

    results = [{"label": "006-pneumatic-cylinder-coulomb_friction@junction:piston", "plant": "pneumatic-cylinder",
                "kind": "coulomb_friction", "generator_error": "BenchmarkError: the effect could not be sized"}]
    summary = summarise(results)
    assert summary["headline"]["scored"] == 0 and summary["headline"]["generator_errors"] == 1
    write_report(results, summary, tmp_path, seed=7531)
    assert (tmp_path / "results.png").stat().st_size > 0 and "generator" in (tmp_path / "results.md").read_text()


def test_the_pam_truths_signals_survive_a_run_gone_to_infinity():
    """A calibration probe may drive the joint out of range: its signals are NaN, not a raise."""
    from diagnosis.benchmark.plants_pam import pam

    sig = pam().signals(np.array([np.inf, 1.0, 4e5, 4e5]), {})
    assert np.isnan(sig["muscle1"]) and np.isnan(sig["muscle2"])


def test_a_second_effect_the_first_hides_is_measured_invisible():
    """Seed 3434, compound case 006: Coulomb friction on the geared inertias' first shaft and a speed
    sensor on it that clips at 90 % of the nominal's range, each sized alone.  With the friction the
    shaft never reaches the range: the truth with both is the friction's alone, to rounding (the
    second's effect-to-noise 0), while the friction's stands out of the noise."""
    from diagnosis.benchmark.compound import realise_compound, second_effect
    spec = draw_cases(80, 3434, PLANTS_BEFORE_34, KINDS_BEFORE_32)[6]
    plant = PLANTS[spec.plant]()
    second = second_effect(spec, plant, KINDS_BEFORE_32)
    assert (spec.kind, second.kind, second.door) == ("coulomb_friction", "saturation", "output")
    rec = realise_compound(spec, second, plant)
    first, also = rec.visible
    assert also < 1e-6 and first > RATIOS[0]


def test_a_compound_case_draws_a_second_effect_a_rig_could_have_besides():
    """--compound: each effect case gets a second effect of another kind, reproducibly, never a
    second friction law at the same 1-junction or a rigidly geared one, the same input or output
    twice, or a second change of the same storage; null cases stay null."""
    from diagnosis.benchmark.compound import FRICTIONS, compound_label, second_effect
    specs = draw_cases(80, 3434, PLANTS)
    seconds = [second_effect(s, PLANTS[s.plant]()) for s in specs]
    assert seconds == [second_effect(s, PLANTS[s.plant]()) for s in specs]
    for first, second in zip(specs, seconds):
        if first.kind == "none":
            assert second is None and compound_label(first, second) == first.label
            continue
        assert second is not None and second.kind != first.kind
        assert (second.seed, second.excitation, second.ratio) == (first.seed, first.excitation, first.ratio)
        if (second.door, second.name) == (first.door, first.name):
            assert second.door == "junction"
        plant = PLANTS[first.plant]()
        j1, j2 = (s.name if s.door == "junction" else None for s in (first, second))
        if j1 and j2 and (j1 == j2 or j2 in plant.junction(j1).equivalent):
            assert not {first.kind, second.kind} <= set(FRICTIONS), (first, second)
        assert compound_label(first, second) == f"{first.label}+{second.kind}@{second.door}:{second.name}"
    assert len({s.kind for s in seconds if s is not None}) >= 10


def test_a_compound_truth_carries_both_effects_and_is_scored_on_each():
    """A constant load at the msd's mass and an offset of its position sensor, each sized alone on
    the same commands: on the linear plant the truth with both is the load's truth plus the offset,
    to rounding.  The score names which effect some answer found."""
    from diagnosis.benchmark.compound import realise_compound
    from diagnosis.benchmark.run import score_case
    load = CaseSpec(0, 31, "msd", "constant_load", "junction", "v_mass", target_change=0.1, ratio=10.0)
    offset = CaseSpec(0, 31, "msd", "sensor_offset", "output", "x", target_change=0.05, ratio=10.0)
    plant = PLANTS["msd"]()
    alone = realise(load, plant)
    rec = realise_compound(load, offset, plant)
    assert rec.also.effect.kind == "sensor_offset" and rec.also.effect.m != 0.0
    np.testing.assert_allclose(rec.truth["x"], alone.truth["x"] + rec.also.effect.m, rtol=0, atol=1e-9)
    np.testing.assert_allclose(rec.truth["v"], alone.truth["v"], rtol=0, atol=1e-12)
    assert rec.sigma == alone.sigma
    both = {"missing_physics": [{"kind": "constant_load", "attached_to": "junction v_mass", "parameters": {}},
                                {"kind": "sensor_offset", "attached_to": "output x", "parameters": {}}],
            "fit": {"nominal": {}, "improved": {}}}
    s = score_case(rec, both)
    assert (s.first_found, s.also_found, s.also_kind, s.also_place) == (True, True, "sensor_offset", "output x")
    one = {**both, "missing_physics": both["missing_physics"][1:]}
    assert (score_case(rec, one).first_found, score_case(rec, one).also_found) == (False, True)
    # the load stated as not told apart from the offset counts at the load's own place, not elsewhere
    for place, named in (("junction v_mass", True), ("junction other", False)):
        one["missing_physics"][0]["indistinguishable"] = [{"kind": "constant_load", "place": place}]
        assert score_case(rec, one).first_found is named
    base = dict(seconds_diagnose=1.0, place_ok=True, answer_place="", plant="msd", improvement=0.9, kind="leak",
                answer_kind="leak", kind_ok=True, also_kind="sensor_offset")
    h = summarise([dict(base, label="a", first_found=True, also_found=True),
                   dict(base, label="b", first_found=True, also_found=False)])["headline"]
    assert (h["compound_cases"], h["first_found"], h["second_found"], h["both_found"]) == (2, 1.0, 0.5, 0.5)
    assert "| compound cases (2, two concealed effects; the second visible in 2, both in 2): some answer names " \
           "the first / the second / both | 100 % / 50 % / 50 % | |" in markdown(summarise(
               [dict(base, label="a", first_found=True, also_found=True),
                dict(base, label="b", first_found=True, also_found=False)]), seed=0)
    # a second effect the first hides in the truth with both is not asked for
    h = summarise([dict(base, label="a", first_found=True, also_found=True, first_visible=9.0, also_visible=4.0),
                   dict(base, label="b", first_found=True, also_found=False, first_visible=9.0,
                        also_visible=0.5)])["headline"]
    assert (h["second_visible"], h["both_visible"], h["second_found"], h["both_found"]) == (1, 1, 1.0, 1.0)
    assert "compound_cases" not in summarise([dict(base, label="c", also_kind="")])["headline"]


def test_an_input_offset_and_the_constant_load_its_source_makes_are_one_answer():
    """A force's offset on the mass-spring-damper is a constant force at its mass (no recording
    tells them apart): either answer scores the other right; a valve voltage's is no load."""
    from types import SimpleNamespace
    from diagnosis.benchmark.run import score_case
    msd, pam = PLANTS["msd"](), PLANTS["pam"]()
    load = make_effect("constant_load", msd, "junction", "v_mass", 0.1, {}, {"sign": 1.0})
    offset = make_effect("input_offset", msd, "input", "F", 0.1, {}, {"sign": 1.0})
    assert load.equivalent_answers() == {("input_offset", "input F")}
    assert offset.equivalent_answers() == {("constant_load", "junction v_mass")}
    assert make_effect("input_offset", pam, "input", "u1", 0.1, {}, {"sign": 1.0}).equivalent_answers() == set()
    spec = CaseSpec(0, 5, "msd", "input_offset", "input", "F", target_change=0.1, ratio=10.0)
    rec = SimpleNamespace(spec=spec, plant=msd, change=0.1, nominal_drifts=False, affected="x", effect=offset)
    answer = {"missing_physics": [{"kind": "constant_load", "attached_to": "junction v_mass", "parameters": {}}],
              "fit": {"nominal": {"x": 0.2}, "improved": {"x": 0.01}}}
    s = score_case(rec, answer)
    assert s.kind_ok and s.place_ok
    answer["missing_physics"][0]["attached_to"] = "junction elsewhere"
    assert not score_case(rec, answer).kind_ok


def test_a_prbs_of_few_long_bits_switches_at_least_once():
    """The pneumatic cylinder's pressure holds 20 s bits over an 80 s record: one draw in 32 had
    them all alike, a constant pressure and a load-cell force with no spread, against which no
    effect could be sized (seed 3636, case 037: a generator error).  Every draw now switches."""
    from diagnosis.benchmark.draw import excitation

    plant = PLANTS["pneumatic-cylinder"]()
    t = np.arange(int(plant.duration * plant.rate) + 1) / plant.rate
    assert all(np.ptp(excitation(plant, t, np.random.default_rng(seed), "prbs")["p"]) > 0 for seed in range(200))
    spec = draw_cases(40, 3636, PLANTS, KINDS_BEFORE_36)[37]
    assert spec.label == "037-pneumatic-cylinder-relaxation@junction:piston"
    rec = realise(spec, PLANTS[spec.plant]())
    assert rec.change == pytest.approx(spec.target_change, rel=0.3)
