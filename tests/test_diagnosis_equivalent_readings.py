"""Twins an answer reads as (diagnosis.equivalent_readings): one-parameter scalings no recording of
the signals tells apart from an answered effect, against the plants' scaling symmetries worked out
by hand.

* A force-driven carriage with a viscous friction, ``m v' = g F - b v``: a gain g on F is
  ``(m/g) v' = F - (b/g) v``, so 1 % of gain reads as -1 % of m and -1 % of b.
* A mass-spring-damper, ``m x'' + b x' + k x = g F``: the gain needs m, b and k scaled together; the
  stiffness alone cannot absorb it.
* A linear plant with one output: a gain on its input is a gain on its sensor (with the start state
  free), ``y = g (G * F) + free response``.
"""
import re

import numpy as np
import pytest

from diagnosis.catalogue import candidates
from diagnosis.equivalent_readings import swapped_readings
from diagnosis.place import Place
from diagnosis.recording import Experiment
from msd_truth import rk4_states


def _excitation(t, seed=0):
    rng = np.random.default_rng(seed)
    levels = rng.uniform(-10.0, 10.0, int(np.ceil(t[-1] / 0.5)) + 1)
    return levels[(t // 0.5).astype(int)] + 3.0 * np.sin(2 * np.pi * 0.7 * t)


def _one(graph, place, kind):
    return next(c for c in candidates(graph, place) if c.kind == kind)


def _swap(text: str) -> dict:
    """``{name: value or factor}`` from an Alternative's ``structural`` sentence."""
    out = {name: float(v) for name, v in re.findall(r"(\w+) = ([\d.e+-]+)", text)}
    return out | {name: float(v) for name, v in re.findall(r"(\w+) x ([\d.e+-]+)", text)}


def test_an_input_gain_on_a_carriage_reads_as_its_mass_with_the_friction_scaled():
    from plants import library
    graph = library.build("carriage")
    t = np.arange(0.0, 4.0, 0.005)
    F = _excitation(t)
    exp = Experiment(t, {"F": F}, {"x": np.zeros_like(t), "v": np.zeros_like(t)}, {"F": "N", "x": "m", "v": "m/s"})
    friction = _one(graph, Place("junction", "v_cart"), "viscous_friction")
    mass = _one(graph, Place("junction", "v_cart"), "nominal_value")
    b = friction.params[0].name
    answer = friction.build(graph, {b: 6.0}).with_params({"m": 24.0})
    found = swapped_readings(answer, [friction, mass], exp, None, {"x": 1e-3, "v": 1e-3})
    # the gain reads as the mass (one parameter, in the span with the friction's scaled), not as the friction
    assert list(found) == [1]
    (twin,) = found[1]
    assert (twin.kind, twin.place) == ("input_gain", "input F")
    # the mass back at its nominal 20 kg: g = 20/24 on F, and the friction scaled by the same g
    swap = _swap(twin.structural)
    assert swap["gain_F"] == pytest.approx(20 / 24, rel=1e-3)
    assert swap[b] == pytest.approx(20 / 24, rel=1e-3)
    assert twin.difference < 0.05
    assert twin.to_json()["structural"] == twin.structural and twin.to_json()["z"] is None


def test_a_mass_spring_dampers_stiffness_alone_does_not_absorb_an_input_gain():
    from plants import library
    graph = library.build("mass-spring-damper")
    t = np.arange(0.0, 8.0, 0.01)
    exp = Experiment(t, {"F": _excitation(t, 1)}, {"x": np.zeros_like(t)}, {"F": "N", "x": "m"})
    stiffness = next(c for c in candidates(graph, Place("junction", "v_mass"))
                     if c.kind == "nominal_value" and c.target == "k")
    found = swapped_readings(graph, [stiffness], exp, None, {"x": 1e-4})
    assert all(a.kind != "input_gain" for twins in found.values() for a in twins)


def test_on_a_linear_plant_with_one_output_an_input_gain_is_its_sensors_gain():
    from plants import library
    graph = library.build("mass-spring-damper")
    t = np.arange(0.0, 8.0, 0.01)
    exp = Experiment(t, {"F": _excitation(t, 2)}, {"x": np.zeros_like(t)}, {"F": "N", "x": "m"})
    gain = _one(graph, Place("input", "F"), "input_gain")
    answer = gain.build(graph, {gain.params[0].name: 1.3})
    found = swapped_readings(answer, [gain], exp, {"q_k": 0.05, "p_m": 0.0}, {"x": 1e-4})
    twins = {(a.kind, a.place): a for a in found[0]}
    assert set(twins) == {("sensor_gain", "output x")}
    # the gain back at 1, the sensor reads 1.3 times the motion (the start state refitted: x0 / 1.3)
    assert _swap(twins["sensor_gain", "output x"].structural)["gain_x"] == pytest.approx(1.3, rel=1e-3)


def test_the_carriages_sensor_gain_on_one_of_two_outputs_is_no_twin_of_its_input_gain():
    from plants import library
    graph = library.build("carriage")
    t = np.arange(0.0, 4.0, 0.005)
    exp = Experiment(t, {"F": _excitation(t, 3)}, {"x": np.zeros_like(t), "v": np.zeros_like(t)},
                     {"F": "N", "x": "m", "v": "m/s"})
    gain = _one(graph, Place("input", "F"), "input_gain")
    found = swapped_readings(gain.build(graph, {gain.params[0].name: 0.8}), [gain], exp, None,
                             {"x": 1e-3, "v": 1e-3})
    twins = {(a.kind, a.place): a for a in found.get(0, [])}
    assert set(twins) == {("nominal_value", "junction v_cart")}       # m/g: the mass alone is the gain here
    assert _swap(twins["nominal_value", "junction v_cart"].structural)["m"] == pytest.approx(25.0, rel=1e-3)


def test_end_to_end_a_carriage_with_an_actuator_gain_and_friction_names_both_readings(tmp_path):
    """m v' = g F - b v (m = 20 kg, g = 0.7, b = 8 N s/m) by the tests' own RK4, x and v measured:
    the recording cannot tell the gain from the mass, and the report says so for whichever it names."""
    from diagnosis.diagnose import diagnose
    from diagnosis.recording import Recording
    rng = np.random.default_rng(5)
    t = np.arange(0.0, 10.0, 0.005)
    F = _excitation(t, 5) * 4.0

    def rate(s, f):
        return np.array([s[1], (0.7 * f - 8.0 * s[1]) / 20.0])

    xv = rk4_states(rate, t, F, substeps=5)
    rec = Recording.from_arrays(t, {"F": F, "x": xv[:, 0] + rng.normal(0, 2e-3, t.size),
                                    "v": xv[:, 1] + rng.normal(0, 2e-3, t.size)})
    rep = diagnose("carriage", rec, inputs=["F=F:N"], outputs=["x=x:m", "v=v:m/s"]).to_json()
    found = [e for e in rep["missing_physics"] if e["kind"] != "none"]
    named = {(e["kind"], e["attached_to"]) for e in found}
    listed = {(a["kind"], a["place"]) for e in found for a in e.get("indistinguishable", [])}
    assert ("viscous_friction", "junction v_cart") in named
    readings = {("input_gain", "input F"), ("nominal_value", "junction v_cart")}
    assert readings & named and readings <= named | listed


def test_candidates_propose_only_the_kinds_asked_for():
    from plants import library
    msd = library.build("mass-spring-damper")
    assert [c.kind for c in candidates(msd, Place("output", "x"), kinds=("sensor_gain",))] == ["sensor_gain"]
    values = [c.target for c in candidates(msd, Place("junction", "v_mass"), kinds=("nominal_value",))]
    assert sorted(values) == ["b", "k", "m"]
