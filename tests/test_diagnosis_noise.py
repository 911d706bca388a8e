"""Noise level: estimated from the measurement and the nominal residual, or given by the user."""
from __future__ import annotations

import numpy as np
import pytest

from diagnosis.benchmark.draw import CaseSpec, realise
from diagnosis.benchmark.plants import PLANTS
from diagnosis.benchmark.run import bindings, write_csv
from diagnosis.diagnose import diagnose
from diagnosis.errors import DiagnosisError
from diagnosis.residuals import noise_sigma


@pytest.fixture(scope="module")
def null_recording(tmp_path_factory):
    rec = realise(CaseSpec(0, 31, "msd", "none", noise_share=0.01), PLANTS["msd"]())
    path = tmp_path_factory.mktemp("noise") / "msd.csv"
    write_csv(rec, path, np.random.default_rng(32))
    return rec, path


def test_a_fast_signal_is_not_taken_for_noise():
    # a resonance at 0.35 of the sampling rate: the signal's own second differences are large
    t = np.arange(20000) / 200.0
    clean = 0.5 * np.sin(2 * np.pi * 70 * t) + 0.2 * np.sin(2 * np.pi * 0.3 * t)
    y = np.round((clean + np.random.default_rng(1).normal(0.0, 0.004, t.size)) / 1e-3) * 1e-3
    assert noise_sigma(y) > 10 * 0.004                       # the measurement alone: fooled
    truth = np.hypot(0.004, 1e-3 / np.sqrt(12))
    assert noise_sigma(y, y - clean) == pytest.approx(truth, rel=0.05)


@pytest.mark.parametrize("q", [0.25, 0.5, 1.2, 3.0])
def test_noise_as_coarse_as_the_resolution_is_measured(q):
    # Gaussian noise of 1 read through a resolution q: second differences are whole multiples of
    # q, and so was the median absolute deviation the estimate once was (at q = 1.2 it read 0.69
    # of the noise; a pure-noise output then seemed to hold model error, seed 3131, case 054)
    t = np.arange(20000) / 1000.0
    clean = 20.0 * np.sin(2 * np.pi * 0.3 * t)
    y = np.round((clean + np.random.default_rng(3).normal(0.0, 1.0, t.size)) / q) * q
    truth = np.sqrt(1.0 + q ** 2 / 12)                        # noise and rounding, uncorrelated
    assert noise_sigma(y) == pytest.approx(truth, rel=0.03)
    assert noise_sigma(y, y - clean) == pytest.approx(truth, rel=0.03)


def test_steps_do_not_count_as_noise():
    t = np.arange(20000) / 1000.0
    clean = 30.0 * np.repeat(np.random.default_rng(4).integers(0, 2, 40), 500) + 5.0 * t
    y = clean + np.random.default_rng(5).normal(0.0, 1.0, t.size)
    assert noise_sigma(y) == pytest.approx(1.0, rel=0.03)     # the 20 steps are trimmed


def test_quantisation_floor_is_kept_for_slow_quantised_signals():
    t = np.linspace(0.0, 1.0, 5001)
    y = np.round(0.01 * t / 1e-3) * 1e-3                      # moves 10 counts in 5000 samples
    assert noise_sigma(y, y - 0.01 * t) == pytest.approx(1e-3 / np.sqrt(12), rel=1e-9)


def test_user_noise_replaces_the_estimate(null_recording):
    rec, path = null_recording
    ins, outs = bindings(rec)
    report = diagnose("mass-spring-damper", str(path), inputs=ins, outputs=outs, max_effects=1,
                      noise=["x=2.5:mm"])
    assert "Output x: nominal held-out NRMSE" in report.text and "(noise about 0.0025 m)" in report.text
    assert report.to_json()["missing_physics"][0]["kind"] == "none"


@pytest.mark.parametrize("noise, message", [
    (["y=0.1"], "'y' is not a measured output"),
    (["x=abc"], "is not a number"),
    ({"x": -1.0}, "must be positive"),
    (["x=1:kg"], "noise of x"),
])
def test_bad_noise_is_named(null_recording, noise, message):
    rec, path = null_recording
    ins, outs = bindings(rec)
    with pytest.raises(DiagnosisError, match=message):
        diagnose("mass-spring-damper", str(path), inputs=ins, outputs=outs, noise=noise)
