"""The recording's initial state: fitted to its first samples where the default contradicts them."""
from __future__ import annotations

import numpy as np
import pytest

import plants.library as library
from diagnosis.benchmark.plants import PLANTS
from diagnosis.benchmark.simulate import simulate_truth
from diagnosis.diagnose import diagnose
from diagnosis.initial_state import estimate_initial_state
from diagnosis.recording import Experiment
from diagnosis.residuals import OutputSimulator


def _msd_recording(path, x_start, v_start, seed, sigma=0.002):
    plant = PLANTS["msd"]()
    t = np.arange(0, 30.0, 1 / plant.rate)
    rng = np.random.default_rng(seed)
    F = np.repeat(rng.uniform(-2, 2, t.size // 50 + 1), 50)[:t.size]
    y = simulate_truth(plant, t, {"F": F}, x0=np.array([x_start, v_start]))
    x = y["x"] + rng.normal(0.0, sigma, t.size)
    v = y["v"] + rng.normal(0.0, sigma, t.size)
    rows = "\n".join(f"{a:.4f},{b:.4f},{c:.6f},{d:.6f}" for a, b, c, d in zip(t, F, x, v))
    path.write_text("t,F,x,v\n" + rows + "\n")
    return path


def _displaced_msd():
    """``(sim, exp)``: the mass-spring-damper recorded from x = 0.3 m, v = -0.2 m/s under 0.5 N."""
    t = np.arange(0, 3.0, 0.02)
    F = np.full(t.size, 0.5)
    truth = simulate_truth(PLANTS["msd"](), t, {"F": F}, x0=np.array([0.3, -0.2]))
    exp = Experiment(t, {"F": F}, {"x": truth["x"], "v": truth["v"]}, {"F": "N", "x": "m", "v": "m/s"})
    return OutputSimulator(library.build("mass-spring-damper"), exp), exp


def test_estimate_recovers_a_displaced_start():
    sim, exp = _displaced_msd()
    est = estimate_initial_state(sim, exp, {"x": 1e-3, "v": 1e-3})
    assert est.samples == 20 and est.gain > 0.99
    assert est.values["q_k"] == pytest.approx(0.3, abs=1e-4)          # position
    assert est.values["p_m"] == pytest.approx(-0.2, abs=1e-4)         # momentum, m = 1 kg


def test_a_recording_that_starts_elsewhere_is_no_missing_physics(tmp_path):
    path = _msd_recording(tmp_path / "displaced.csv", 0.4, 0.3, seed=5)
    report = diagnose("mass-spring-damper", str(path), inputs=["F=F:N"], outputs=["x=x:m", "v=v:m/s"],
                      max_effects=1)
    data = report.to_json()
    assert data["missing_physics"][0]["kind"] == "none"
    assert data["fit"]["start"].startswith("a state estimated from the first")


def test_a_persistent_offset_is_not_absorbed_into_the_start(tmp_path):
    path = _msd_recording(tmp_path / "rest.csv", 0.0, 0.0, seed=6)
    text = path.read_text().splitlines()
    shifted = [text[0]] + [",".join(r.split(",")[:2] + [f"{float(r.split(',')[2]) + 0.05:.6f}"]
                                    + r.split(",")[3:]) for r in text[1:]]
    path.write_text("\n".join(shifted) + "\n")
    report = diagnose("mass-spring-damper", str(path), inputs=["F=F:N"], outputs=["x=x:m", "v=v:m/s"],
                      max_effects=1)
    data = report.to_json()
    assert data["fit"]["start"] == "the model's initial state"
    assert (data["missing_physics"][0]["kind"], data["missing_physics"][0]["attached_to"]) == \
        ("sensor_offset", "output x")


def test_the_start_is_estimated_again_in_a_candidate_that_acts_on_the_first_samples(tmp_path):
    """A carriage starts at x = 0 under a position sensor that reads nothing below 0.1 m.  The
    nominal's start, estimated from the clipped first samples, sits at the clip: from there no
    range explains the rest, which reads 0.1 m too high, and the answer was a sensor offset.
    Estimated in the candidate's own model (the range clips those samples, so they no longer
    pull the position up), the start stays at rest and the range is found (seed 7171, case 035)."""
    plant = PLANTS["carriage"]()
    t = np.arange(0, 10.0, 1 / plant.rate)
    rng = np.random.default_rng(11)
    F = np.repeat(rng.uniform(-4.0, 4.0, t.size // 40 + 1), 40)[:t.size]
    F[:100] = 8.0                                                  # off the clip within 0.6 s
    y = simulate_truth(plant, t, {"F": F})
    assert y["x"][0] == 0.0 and np.mean(y["x"] < 0.1) > 0.02       # clipped at the start, and later
    x = np.clip(y["x"], 0.1, None) + rng.normal(0.0, 0.002, t.size)
    v = y["v"] + rng.normal(0.0, 0.0005, t.size)
    rows = "\n".join(f"{a:.4f},{b:.5f},{c:.6f},{d:.6f}" for a, b, c, d in zip(t, F, x, v))
    path = tmp_path / "clipped.csv"
    path.write_text("t,F,x,v\n" + rows + "\n")
    report = diagnose("carriage", str(path), inputs=["F=F:N"], outputs=["x=x:m", "v=v:m/s"], max_effects=1)
    found = report.to_json()["missing_physics"][0]
    assert (found["kind"], found["attached_to"]) == ("saturation", "output x")
    assert found["parameters"]["y_min_x"] == pytest.approx(0.1, abs=0.01)
    assert "re-estimated with saturation at output x" in report.to_json()["fit"]["start"]


def test_an_estimate_of_some_states_keeps_the_others_at_their_defaults():
    sim, exp = _displaced_msd()
    est = estimate_initial_state(sim, exp, {"x": 1e-3, "v": 1e-3}, states=["q_k"])
    assert est.values["p_m"] == sim.initial_state(None)[sim.model.state_index["p_m"]]
    assert est.values["q_k"] != pytest.approx(0.3, abs=1e-4)     # the momentum's error is left to it
    assert estimate_initial_state(sim, exp, {"x": 1e-3, "v": 1e-3}, params={"k": 1.0}).samples == 20
