"""The diagnosis test set (diagnosis.cases): committed recordings, manifest, truth models.

References: the committed CSV files and ``cases.json`` in tests/data/diagnosis
(written by ``python -m diagnosis.cases``); the nominal models of
``plants.library``; unit conversions by ``diagnosis.units.convert``
(written separately from the generator's own scale factors).
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

import plants.library as library
from diagnosis.cases import CASES, case, record, simulate_case
from diagnosis.cases import profiles
from diagnosis.cases.truth import InputDelay, InputSaturation, SensorGain, SensorOffset
from diagnosis.place import Place
from diagnosis.units import convert

DATA = Path(__file__).parent / "data" / "diagnosis"
MANIFEST = json.loads((DATA / "cases.json").read_text())["cases"]
BY_NAME = {e["name"]: e for e in MANIFEST}
# issue 6, section 2c, in its order
VOCABULARY = ("coulomb_friction", "viscous_friction", "stribeck_friction", "pressure_dependent_friction",
              "leak", "heat_transfer", "valve_lag", "transport_delay", "hysteresis", "backlash",
              "nonlinear_stiffness", "saturation", "sensor_offset", "sensor_gain")
EFFECT_CASES = [c.name for c in CASES if c.effect is not None]
NULL_CASES = [c.name for c in CASES if c.effect is None]


def _read(name: str) -> dict[str, np.ndarray]:
    text = (DATA / BY_NAME[name]["file"]).read_text().splitlines()
    header = text[0].split(",")
    values = np.array([[float(x) for x in row.split(",")] for row in text[1:]])
    return {col: values[:, k] for k, col in enumerate(header)}


def _commands(name: str, stop: float | None = None):
    """Sample times and model-unit commands read back from the committed CSV."""
    c, cols = case(name), _read(name)
    t = cols[c.time_column]
    n = len(t) if stop is None else int(np.searchsorted(t, stop)) + 1
    return t[:n], {s.name: cols[s.column][:n] / s.scale for s in c.inputs}


# -- the set as a whole --------------------------------------------------------------------------

def test_the_set_covers_the_issue():
    kinds = [c.kind for c in CASES if c.effect is not None]
    assert len(kinds) >= 10 and len(set(kinds)) >= 8 and len(set(kinds)) == len(kinds)
    assert set(kinds) <= set(VOCABULARY)
    assert len({case(n).model for n in NULL_CASES}) >= 2
    models = {c.model for c in CASES}
    assert {"pam", "exoskeleton"} <= models and len(models - {"pam", "exoskeleton"}) >= 3
    assert models <= set(library.names())
    sizes = [(DATA / e["file"]).stat().st_size for e in MANIFEST]
    assert max(sizes) < 300e3 and sum(sizes) < 3e6
    for c in CASES:
        assert 100.0 <= c.rate <= 1000.0 and 10.0 <= c.duration <= 40.0, c.name


def test_manifest_is_the_definitions():
    assert [e["name"] for e in MANIFEST] == [c.name for c in CASES]
    for c in CASES:
        e = BY_NAME[c.name]
        assert (e["model"], e["kind"], e["seed"], e["affected_output"], e["time"]) == \
            (c.model, c.kind, c.seed, c.affected, c.time_column)
        if c.effect is None:
            assert e["place"] is None and e["parameters"] == {}
        else:
            assert Place(**e["place"]) == c.effect.place
            assert {k: v["value"] for k, v in e["parameters"].items()} == \
                {p.name: p.value for p in c.effect.params}
            assert all(v["unit"] for v in e["parameters"].values())
        assert [Place(**q) for q in e["equivalent_places"]] == list(c.equivalent)
        for s in c.outputs:
            assert e["noise"][s.name]["effective_sigma"] == pytest.approx(math.hypot(s.sigma, s.quantum / 12 ** 0.5), rel=1e-5)


@pytest.mark.parametrize("name", [c.name for c in CASES])
def test_bindings_name_real_signals_and_columns(name):
    e, graph = BY_NAME[name], library.build(BY_NAME[name]["model"])
    model_inputs = {d.name: d.unit for d in graph.inputs()}
    model_outputs = {o.name: o.unit for o in graph.outputs.values()}
    cols = _read(name)
    assert e["time"] in cols and np.all(np.diff(cols[e["time"]]) > 0)
    c = case(name)
    for kind, bindings, known in (("input", e["inputs"], model_inputs), ("output", e["outputs"], model_outputs)):
        for binding in bindings:
            model_name, _, rest = binding.partition("=")
            column, _, unit = rest.partition(":")
            assert model_name in known, f"{name}: {kind} {model_name!r} not in {sorted(known)}"
            assert column in cols, f"{name}: no column {column!r}"
            # the generator's scale factor agrees with the independent unit converter
            signal = next(s for s in c.inputs + c.outputs if s.name == model_name)
            assert float(convert(signal.scale, unit, known[model_name])) == pytest.approx(1.0, rel=1e-12)
    assert e["affected_output"] in model_outputs


@pytest.mark.parametrize("name", [c.name for c in CASES if c.equivalent])
def test_equivalent_places_are_rigidly_geared_junctions(name):
    """An equivalent junction is a 1-junction joined to the effect's 1-junction through one TF:
    the flows are a fixed multiple of each other and an extra effort at one enters the same
    equation of motion as the TF-scaled effort at the other."""
    c = case(name)
    graph = library.build(c.model)
    for other in c.equivalent:
        assert other.kind == c.effect.place.kind == "junction"
        neighbours = {n: {b.head.element if end == "tail" else b.tail.element for b, end in graph.bonds_of(n)}
                      for n in (c.effect.place.name, other.name)}
        shared = neighbours[c.effect.place.name] & neighbours[other.name]
        assert [graph.elements[n].kind for n in shared] == ["TF"]
        assert graph.elements[other.name].kind == graph.elements[c.effect.place.name].kind == "1"


# -- the generator -------------------------------------------------------------------------------

@pytest.mark.parametrize("name", ["msd_coulomb", "tanks_sensor_offset"])
def test_generator_reproduces_the_committed_recording(name):
    fresh = record(case(name)).csv().splitlines()
    committed = (DATA / BY_NAME[name]["file"]).read_text().splitlines()
    assert fresh[0] == committed[0] and len(fresh) == len(committed)
    a = np.array([[float(x) for x in r.split(",")] for r in fresh[1:]])
    b = np.array([[float(x) for x in r.split(",")] for r in committed[1:]])
    quanta = [0.0] + [s.quantum for s in case(name).inputs + case(name).outputs]
    # identical, except that a value on a rounding boundary may flip by one count (float precision)
    assert np.all(np.abs(a - b) <= np.array(quanta) * 1.001 + 1e-12)
    assert np.mean(a != b) < 1e-3


def test_profiles():
    t = np.arange(0, 12.0, 0.01)
    stairs = profiles.staircase(t, amplitude=6.0, step_time=0.25, n_levels=12)
    assert stairs[0] == 0.0 and stairs.max() == 6.0 and stairs.min() == -6.0
    assert np.allclose(np.unique(np.abs(np.diff(stairs))), [0.0, 0.5])
    rng = np.random.default_rng(1)
    levels = profiles.held_levels(t, rng, low=-1.0, high=2.0, hold=(0.5, 1.0))
    changes = np.flatnonzero(np.diff(levels)) + 1
    assert levels.min() >= -1.0 and levels.max() <= 2.0
    assert np.all(np.diff(t[changes]) >= 0.5 - 0.011) and np.all(np.diff(t[changes]) <= 1.0 + 0.011)
    bits = profiles.prbs(t, rng, low=-0.2, high=0.2, bit_time=0.15)
    assert set(np.unique(bits)) == {-0.2, 0.2}
    assert np.array_equal(profiles.dac([0.0149, -7.0], 0.01, low=-5.0), [0.01, -5.0])


# -- truth models --------------------------------------------------------------------------------

def test_signal_effects_by_hand():
    t = np.array([0.0, 0.1, 0.2])
    delayed = InputDelay("transport_delay", Place("input", "u"), ()).inputs  # params not needed below
    with pytest.raises(KeyError, match="delay"):
        delayed(t, {"u": np.array([1.0, 2.0, 3.0])})
    d = case("exo_delay").effect
    times, values = d.inputs(t, {"tau_m": np.array([1.0, 2.0, 3.0])})["tau_m"]
    assert np.allclose(times, t + 0.002) and np.array_equal(values, [1.0, 2.0, 3.0])
    s = InputSaturation("saturation", Place("input", "V"), case("dcmotor_saturation").effect.params)
    assert np.array_equal(s.inputs(t, {"V": np.array([-14.0, 3.0, 12.0])})["V"][1], [-10.0, 3.0, 10.0])
    g = SensorGain("sensor_gain", Place("output", "v_C"), case("rlc_sensor_gain").effect.params)
    assert np.allclose(g.outputs({"v_C": np.array([2.0]), "i": np.array([1.0])})["v_C"], [1.9])
    o = SensorOffset("sensor_offset", Place("output", "h2"), case("tanks_sensor_offset").effect.params)
    assert np.allclose(o.outputs({"h2": np.array([0.25])})["h2"], [0.26])
    with pytest.raises(KeyError, match="no parameter"):
        g.with_values(gian=1.0)
    with pytest.raises(KeyError, match="msd_coulomb"):
        case("msd_colomb")


@pytest.mark.parametrize("name", EFFECT_CASES)
def test_truth_without_its_effect_is_the_nominal_model(name):
    c = case(name)
    t, commands = _commands(name, stop=2.0)
    nominal = simulate_case(c, t, commands, truth=False)
    neutral = simulate_case(c, t, commands, effect=c.effect.neutral())
    for s in c.outputs:
        tol = 1e-3 * s.effective_sigma / s.scale
        assert np.max(np.abs(neutral[s.name] - nominal[s.name])) < tol, s.name


def test_valve_lag_tends_to_the_nominal_valve():
    c = case("pam_valve_lag")
    t, commands = _commands(c.name, stop=2.0)
    nominal = simulate_case(c, t, commands, truth=False)["psi"]
    fast = simulate_case(c, t, commands, effect=c.effect.with_values(tau=0.5e-3))["psi"]
    slow = simulate_case(c, t, commands)["psi"]
    sigma = c.output("psi").effective_sigma
    rms = lambda d: float(np.sqrt(np.mean(d ** 2)))   # noqa: E731
    # the lag's effect shrinks with tau (about in proportion): 0.5 ms is well inside the noise
    assert rms(fast - nominal) < 0.5 * sigma < 5 * sigma < rms(slow - nominal)
    assert rms(fast - nominal) < rms(slow - nominal) / 40


# -- the committed recordings against the nominal model ------------------------------------------

@pytest.mark.parametrize("name", [c.name for c in CASES])
def test_effect_above_noise_and_nulls_noise_only(name):
    """Recorded minus nominal-simulated output (column units): for an effect case its RMS,
    less the noise in quadrature, over the effective sigma must reach the documented floor and
    agree with the manifest's noise-free figure; for a null case every output's residual has
    the documented sigma (within 20 %) and no bias."""
    c, e, cols = case(name), BY_NAME[name], _read(name)
    t, commands = _commands(name)
    nominal = simulate_case(c, t, commands, truth=False)
    for s in c.outputs:
        residual = cols[s.column] - s.scale * nominal[s.name]
        sigma = e["noise"][s.name]["effective_sigma"]
        if c.effect is None:
            assert 0.8 * sigma < np.std(residual) < 1.2 * sigma, s.name
            assert abs(np.mean(residual)) < 4 * sigma / np.sqrt(len(residual)), s.name
        elif s.name == c.affected:
            ratio = math.sqrt(max(np.mean(residual ** 2) - sigma ** 2, 0.0)) / sigma
            assert ratio >= e["min_effect_to_noise"] >= 5.0
            assert ratio == pytest.approx(e["effect_to_noise"], rel=0.1)
            # the held-out tail (last 30 %) shows it too: a 50 % lower held-out NRMSE is possible
            # only if the effect there exceeds sqrt(3) sigma; ask for 3
            tail = residual[t >= t[-1] - 0.3 * (t[-1] - t[0])]
            held = math.sqrt(max(np.mean(tail ** 2) - sigma ** 2, 0.0)) / sigma
            assert held >= 3.0
            assert held == pytest.approx(e["holdout_effect_to_noise"], rel=0.15)
