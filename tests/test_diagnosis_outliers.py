"""Isolated spikes (diagnosis.outliers): a sensor glitch's single samples are found and replaced;
a signal's own sharp features (steps, an extremum, an input's pulse an output reads, a slip that
moves two sensors) are not."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from diagnosis.diagnose import diagnose
from diagnosis.errors import DiagnosisError
from diagnosis.outliers import MOST, isolated_spikes, without_spikes
from diagnosis.recording import Experiment

DATA = Path(__file__).parent / "data" / "diagnosis"
T = np.arange(0.0, 20.0, 0.01)
SIGMA = 0.01


def _experiment(outputs, inputs=None):
    return Experiment(T, inputs if inputs is not None else {"u": np.sign(np.sin(0.7 * T))}, outputs, {}, "test")


@pytest.fixture
def noisy():
    rng = np.random.default_rng(11)
    clean = np.sin(1.3 * T) + 0.5 * np.sign(np.sin(0.7 * T))          # smooth, with steps
    return clean, clean + SIGMA * rng.standard_normal(T.size)


def test_a_glitchs_samples_are_found_and_replaced_by_their_neighbours_mean(noisy):
    clean, y = noisy
    glitch = {300: 0.4, 1234: -0.25, 1700: 0.6}                      # 25-60 noise standard deviations
    spiky = y.copy()
    for k, a in glitch.items():
        spiky[k] += a
    exp = _experiment({"y": spiky})
    # the nominal misses the amplitude by 10 %: model error, smooth, is no spike
    found = isolated_spikes(exp, {"y": 0.9 * clean}, {"y": SIGMA})
    assert list(found) == ["y"] and found["y"].tolist() == sorted(glitch)
    repaired = without_spikes(exp, found).outputs["y"]
    assert np.abs(repaired[sorted(glitch)] - clean[sorted(glitch)]).max() < 5 * SIGMA
    assert np.array_equal(np.delete(repaired, sorted(glitch)), np.delete(y, sorted(glitch)))
    assert np.array_equal(exp.outputs["y"], spiky)                  # the experiment given is unchanged


def test_a_clean_recording_noisy_or_smooth_has_none(noisy):
    clean, y = noisy
    assert isolated_spikes(_experiment({"y": y}), {"y": 0.9 * clean}, {"y": SIGMA}) == {}
    # noise-free: an extremum stands out of its neighbours by its curvature, as they curve
    smooth = np.sin(3.0 * T)
    assert isolated_spikes(_experiment({"y": smooth}), {"y": np.sin(2.9 * T)}, {"y": 0.0}) == {}


def test_an_inputs_pulse_an_output_reads_is_no_glitch():
    """A command with one-sample pulses, read directly by the output (a force p A): the nominal
    has them too; read two samples late (a transport delay the nominal lacks), the input's pulse
    just before tells."""
    rng = np.random.default_rng(3)
    u = np.zeros(T.size)
    u[[200, 900, 1500]] = 1.0
    y = u + SIGMA * rng.standard_normal(T.size)
    assert isolated_spikes(_experiment({"y": y}, {"u": u}), {"y": u}, {"y": SIGMA}) == {}
    late = np.roll(u, 2) + SIGMA * rng.standard_normal(T.size)
    assert isolated_spikes(_experiment({"y": late}, {"u": u}), {"y": u}, {"y": SIGMA}) == {}


def test_a_sample_that_moves_two_sensors_is_the_plants_own(noisy):
    """A slip seen by the speed and the force sensor at once is physics; a glitch hits one sensor."""
    clean, y = noisy
    rng = np.random.default_rng(5)
    z = 2.0 * clean + SIGMA * rng.standard_normal(T.size)
    y, z = y.copy(), z.copy()
    y[800] += 0.5
    z[801] -= 0.5
    assert isolated_spikes(_experiment({"y": y, "z": z}), {"y": clean, "z": 2 * clean}, {"y": SIGMA, "z": SIGMA}) == {}


def test_a_sample_where_the_speed_reverses_is_a_breakaway(noisy):
    """A Stribeck friction's static peak, one sample long, comes where the nominal's speed changes
    sign (seed 2929, case 044: the cylinder's force at each reversal of its rod)."""
    clean, y = noisy
    speed = np.cos(1.3 * T)                                           # reverses near T = 1.208 s
    k = int(np.argmax(T > np.pi / 2 / 1.3))
    spiky = y.copy()
    spiky[k + 1] += 0.5
    assert isolated_spikes(_experiment({"y": spiky}), {"y": clean}, {"y": SIGMA}, states=speed[:, None]) == {}
    assert isolated_spikes(_experiment({"y": spiky}), {"y": clean}, {"y": SIGMA})["y"].tolist() == [k + 1]


def test_too_many_are_the_signals_own(noisy):
    clean, y = noisy
    k = np.arange(50, T.size - 50, 97)[: int(MOST * T.size) + 1]     # one more than MOST allows
    spiky = y.copy()
    spiky[k] += 0.5
    assert isolated_spikes(_experiment({"y": spiky}), {"y": clean}, {"y": SIGMA}) == {}
    assert isolated_spikes(_experiment({"y": np.where(np.isin(np.arange(T.size), k[:-1]), spiky, y)}),
                           {"y": clean}, {"y": SIGMA})["y"].tolist() == k[:-1].tolist()


def test_diagnose_repairs_a_glitchy_sensor_and_says_where(tmp_path):
    """The test set's Coulomb friction on the mass-spring-damper with three glitches of the
    position sensor (one in the training part, two held out): repaired, the held-out error drops
    98 % as on the clean recording; kept, the glitches are half of what is left."""
    data = pd.read_csv(DATA / "msd_coulomb.csv")
    for row, jump in ((700, 40.0), (2400, -300.0), (2700, 250.0)):     # mm; the noise is 0.5 mm
        data.loc[row, "x_mm"] += jump
    path = tmp_path / "glitchy.csv"
    data.to_csv(path, index=False)
    args = dict(time="t_s", inputs=["F=F_N:N"], outputs=["x=x_mm:mm"])
    report = diagnose("mass-spring-damper", str(path), **args).to_json()
    answers = [(m["kind"], m["attached_to"]) for m in report["missing_physics"]]
    assert answers == [("coulomb_friction", "junction v_mass")]
    assert report["fit"]["improved"]["x"] < 0.05 * report["fit"]["nominal"]["x"]
    assert "3 isolated spike(s) at t = 7, 24, 27 s" in report["notes"][0]
    # one round: what is kept is the first answer's error (a second round among the glitches took 24 s)
    kept = diagnose("mass-spring-damper", str(path), spikes="keep", max_effects=1, **args).to_json()
    assert kept["fit"]["improved"]["x"] > 0.4 * kept["fit"]["nominal"]["x"] and "notes" not in kept
    with pytest.raises(DiagnosisError, match="spikes must be 'repair' or 'keep'"):
        diagnose("mass-spring-damper", str(path), spikes="drop", **args)
