"""Constitutive laws as places (diagnosis.law_places): a muscle's force law on the PAM joint.

The reference is the benchmark's hand-written PAM truth (diagnosis.benchmark.plants_pam: its own
RK4 on Python floats, eqs. (2)-(10)), whose ``extra["muscle1"]`` adds a force to muscle 1's
contraction force eqs. (6)-(7); none of its code is the graph's or the catalogue's.
"""
from types import SimpleNamespace

import numpy as np
import pytest

from diagnosis.benchmark.plants_pam import pam_frictionless
from diagnosis.benchmark.simulate import NoEffect, simulate_truth
from diagnosis.catalogue import candidates
from diagnosis.errors import UnknownNameError
from diagnosis.fit import CandidateFit, choose
from diagnosis.graph_location import candidate_places, locate_on_graph
from diagnosis.law_places import law_places, law_ports, split_law, split_laws
from diagnosis.place import Place
from diagnosis.recording import Experiment
from diagnosis.residuals import OutputSimulator
from diagnosis.twins import twin_places
from plants import library


class _MuscleForce(NoEffect):
    """A constant force added to one muscle's law in the truth."""

    def __init__(self, muscle, force):
        self.muscle, self.force = muscle, force

    def extra(self, sig, u, z):
        return {self.muscle: self.force}, np.zeros(0)


@pytest.fixture(scope="module")
def pam():
    return library.build("pam-frictionless")


@pytest.fixture(scope="module")
def run():
    """Two seconds of antagonistic valve commands on the truth joint, 1 kHz."""
    plant = pam_frictionless()
    t = np.arange(0.0, 2.0, 1e-3)
    a = 1.5 * np.sin(2 * np.pi * 0.7 * t)
    return plant, t, {"u1": 5.0 + a, "u2": 5.0 - a}


def _simulated_psi(graph, plant, t, u, psi):
    exp = Experiment(t, u, {"psi": psi}, {"u1": "V", "u2": "V", "psi": "deg"}, "truth")
    return OutputSimulator(graph, exp, outputs=["psi"]).run(None, plant.nominal_x0).outputs["psi"]


def test_the_muscles_force_laws_are_the_pams_law_places(pam):
    ports = law_ports(pam)
    assert [(p.element, p.port, p.sets, p.junction_kind) for p in ports] == [
        ("muscle1", "mech", "effort", "1"), ("muscle2", "mech", "effort", "1")]
    # the valves' flow laws end at the chambers' 0-junctions: those junctions are their places
    assert all(p.element.startswith("muscle") for p in ports)
    assert law_places(library.build("mass-spring-damper")) == []
    assert [str(p) for p in candidate_places(pam)][-2:] == ["law muscle1", "law muscle2"]
    with pytest.raises(UnknownNameError, match="valve1"):
        split_law(pam, Place("law", "valve1"))


def test_splitting_a_law_leaves_the_equations_unchanged(pam):
    split, junctions = split_laws(pam, law_places(pam))
    assert set(junctions.values()) == {"muscle1_mech_law", "muscle2_mech_law"}
    before, after = pam.equations(), split.equations()
    assert before.state_names == after.state_names
    assert all(a.equals(b) for a, b in zip(before.f, after.f))
    assert all(a.equals(b) for a, b in zip(before.h, after.h))


def test_a_constant_force_at_a_muscles_law_is_the_truths_extra_muscle_force(pam, run):
    plant, t, u = run
    force = 5.0                                         # N on muscle 1's contraction force
    truth = simulate_truth(plant, t, u, _MuscleForce("muscle1", force))["psi"]
    nominal = simulate_truth(plant, t, u)["psi"]
    cand = next(c for c in candidates(pam, Place("law", "muscle1")) if c.kind == "constant_load")
    assert cand.place == Place("law", "muscle1", "bond4") or cand.place.kind == "law"
    graph = cand.build(pam, {cand.params[0].name: force})
    psi = _simulated_psi(graph, plant, t, u, truth)
    change = np.max(np.abs(truth - nominal))            # about 2.3 deg
    assert change > 1.0
    assert np.max(np.abs(psi - truth)) < 2e-3 * change
    assert "muscle1" in cand.explain({cand.params[0].name: force})


def test_location_finds_the_law_and_the_seesaw_it_acts_on(pam, run):
    plant, t, u = run
    truth = simulate_truth(plant, t, u, _MuscleForce("muscle2", 0.5))      # 0.2 deg
    rng = np.random.default_rng(4)
    psi = truth["psi"] + 0.01 * rng.standard_normal(t.size)
    exp = Experiment(t, u, {"psi": psi}, {"u1": "V", "u2": "V", "psi": "deg"}, "truth")
    scores = locate_on_graph(pam, exp, x0=plant.nominal_x0)
    share = {str(s.place): s.explained for s in scores}
    # a force at a muscle reaches the angle only through its lever arm: the muscles' laws and the
    # seesaw explain the same (up to r cos(psi)) and rank first; a junction ranks before a law
    assert str(scores[0].place) == "junction seesaw"
    assert {str(s.place) for s in scores[1:3]} == {"law muscle1", "law muscle2"}
    assert share["law muscle2"] > 0.98 and abs(share["law muscle2"] - share["junction seesaw"]) < 0.01
    assert share["input u1"] < 0.9


def test_the_two_muscles_laws_are_twins(pam):
    assert twin_places(pam, Place("law", "muscle1"), candidate_places(pam)) == [Place("law", "muscle2", "bond8")]


def test_a_tie_between_a_junction_and_a_law_goes_to_the_junction():
    def fit(place, held, train):
        cand = SimpleNamespace(kind="hysteresis", place=place)
        return CandidateFit(cand, {}, {"x": train}, {"x": held}, 2, True, "")

    at_law = fit(Place("law", "muscle1"), 0.0270, 0.020)
    at_junction = fit(Place("junction", "seesaw"), 0.0272, 0.021)
    assert choose({"x": 0.12}, [at_law, at_junction], noise={"x": 0.01}) is at_junction
    # a law that fits clearly better (beyond the 2 % tie) wins
    clearly = fit(Place("law", "muscle1"), 0.0200, 0.015)
    assert choose({"x": 0.12}, [clearly, at_junction], noise={"x": 0.01}) is clearly


def test_a_law_acting_on_a_located_junction_is_its_companion(pam):
    from diagnosis.graph_location import PlaceScore
    from diagnosis.law_places import acts_on
    from diagnosis.place_choice import companion_candidates, companions, without_companions

    muscle1, muscle2 = law_places(pam)
    assert acts_on(pam, muscle1) == acts_on(pam, muscle2) == "seesaw"     # through the lever arms

    def score(place, share):
        return PlaceScore(place, share, np.zeros(3), "", None)

    seesaw, chamber = Place("junction", "seesaw"), Place("junction", "chamber1")
    scores = [score(seesaw, 0.96), score(muscle1, 0.96), score(muscle2, 0.96), score(chamber, 0.5)]
    # the laws take no located place's slot: the chamber stays in the top two
    assert [s.place for s in without_companions(pam, scores)] == [seesaw, chamber]
    laws_at = companions(pam, [seesaw, chamber])
    assert laws_at == {"seesaw": [muscle1, muscle2]}

    def fit(kind, held, place=seesaw):
        return CandidateFit(SimpleNamespace(kind=kind, place=place, regime=None), {}, {"x": held}, {"x": held},
                            2, True, "")

    fits = [fit("coulomb_friction", 0.05), fit("hysteresis", 0.02), fit("stribeck_friction", 0.03),
            fit("hysteresis", 0.01, chamber)]
    picked = companion_candidates(fits, laws_at, lambda place: candidates(pam, place))
    # the two kinds that fitted best at the seesaw, at each law
    assert [(c.kind, c.place.name) for c in picked] == [
        ("hysteresis", "muscle1"), ("stribeck_friction", "muscle1"),
        ("hysteresis", "muscle2"), ("stribeck_friction", "muscle2")]
