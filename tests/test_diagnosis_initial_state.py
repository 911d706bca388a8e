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


def test_estimate_recovers_a_displaced_start():
    t = np.arange(0, 3.0, 0.02)
    F = np.full(t.size, 0.5)
    truth = simulate_truth(PLANTS["msd"](), t, {"F": F}, x0=np.array([0.3, -0.2]))
    exp = Experiment(t, {"F": F}, {"x": truth["x"], "v": truth["v"]}, {"F": "N", "x": "m", "v": "m/s"})
    sim = OutputSimulator(library.build("mass-spring-damper"), exp)
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
