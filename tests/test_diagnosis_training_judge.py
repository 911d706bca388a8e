"""The training part judges an effect the held-out part never shows (diagnosis.training_judge).

Truth (hand-written RK4, not the catalogue's code): the library mass-spring-damper driven hard
for the first 8 s and gently after; its position sensor reads nothing above 0.6 m, a level
reached only in the first 8 s.  The held-out part (the last 30 %) stays far below it, so the
held-out error cannot tell the clipped sensor from the nominal model.
"""
from types import SimpleNamespace

import numpy as np
import pytest

from diagnosis.diagnose import diagnose
from diagnosis.fit import CandidateFit
from diagnosis.training_judge import choose_on_training, holdout_change
from msd_truth import msd_positions

FS, SPAN, SIGMA = 50.0, 20.0, 5e-3       # Hz, s, m
Y_MAX = 0.6                             # m, the sensor's upper limit


def _recording(path, clip, seed=5):
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, SPAN, 1.0 / FS)
    amplitude = np.where(t < 4.0, 4.0, 0.1)
    force = amplitude * (np.sin(2 * np.pi * 0.3 * t) + 0.5 * np.sin(2 * np.pi * 0.7 * t + 1.0))
    x = msd_positions(t, force)
    if clip:
        x = np.minimum(x, Y_MAX)
    x = x + rng.normal(0.0, SIGMA, t.size)
    lines = ["t,F,x"] + [f"{a:.6f},{f:.9g},{p:.6g}" for a, f, p in zip(t, force, x)]
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.fixture(scope="module")
def clipped(tmp_path_factory):
    path = _recording(tmp_path_factory.mktemp("clip") / "msd_clipped.csv", clip=True)
    return diagnose("mass-spring-damper", str(path), inputs=["F=F:N"], outputs=["x=x:m"], max_effects=1)


def test_a_sensor_range_seen_only_in_training_is_named_and_judged_there(clipped):
    data = clipped.to_json()
    (effect,) = data["missing_physics"]
    assert (effect["kind"], effect["attached_to"], effect["judged_on"]) == ("saturation", "output x", "training")
    low, high = (effect["parameters"][n] for n in ("y_min_x", "y_max_x"))
    assert high == pytest.approx(Y_MAX, abs=3 * SIGMA)
    assert low <= -1e299                          # never reached: released, not left at a bound
    assert f"reads nothing above {high:.3g} m" in effect["explanation"]
    assert "Judged on the training part" in clipped.text
    # the held-out part cannot show it: its error is the nominal's
    assert data["fit"]["improved"]["x"] == pytest.approx(data["fit"]["nominal"]["x"], rel=0.02)


def test_without_the_clip_nothing_is_found(tmp_path):
    path = _recording(tmp_path / "msd_free.csv", clip=False)
    report = diagnose("mass-spring-damper", str(path), inputs=["F=F:N"], outputs=["x=x:m"], max_effects=1)
    assert report.kind == "none"


def _fit(train, holdout_change_sd, start_share=0.0, evidence=1e4, n_params=1):
    fit = CandidateFit(SimpleNamespace(kind="saturation"), {}, {"x": train}, {"x": 0.1}, n_params, True, "")
    fit.extra.update(holdout_change=holdout_change_sd, start_share=start_share, train_evidence=evidence)
    return fit


def test_the_training_part_answers_only_for_fits_the_held_out_part_cannot_judge():
    floor = {"x": 0.01}
    assert choose_on_training({"x": 0.2}, [_fit(0.02, 0.5)], floor=floor, n_train=1000).extra["judge"] == "training"
    # a fit that changes the held-out prediction is the held-out part's to judge
    assert choose_on_training({"x": 0.2}, [_fit(0.02, 1.5)], floor=floor, n_train=1000) is None
    # explaining under half of the training excess, or evidence mostly at the start, or too little
    assert choose_on_training({"x": 0.2}, [_fit(0.17, 0.5)], floor=floor, n_train=1000) is None
    assert choose_on_training({"x": 0.2}, [_fit(0.02, 0.5, start_share=0.8)], floor=floor, n_train=1000) is None
    assert choose_on_training({"x": 0.2}, [_fit(0.02, 0.5, evidence=5.0)], floor=floor, n_train=1000) is None
    # a nominal whose training error is the noise needs nothing
    assert choose_on_training({"x": 0.0101}, [_fit(0.01, 0.5)], floor=floor, n_train=1000) is None


def test_holdout_change_in_noise_units():
    y = np.zeros(100)
    assert holdout_change({"x": y + 0.02}, {"x": y}, {"x": 0.01}) == pytest.approx(2.0)
    assert holdout_change({"x": y}, {"x": y}, {"x": 0.01}) == 0.0
    assert holdout_change({}, {"x": y}, {"x": 0.01}) == np.inf


def test_holdout_change_leaves_out_the_samples_a_segment_judge_does_not_score():
    # NaN in both predictions: a segment's start-estimation samples; NaN in one only: a run that failed
    y, skipped = np.zeros(100), np.zeros(100)
    skipped[:40] = np.nan
    assert holdout_change({"x": skipped + 0.02}, {"x": skipped}, {"x": 0.01}) == pytest.approx(2.0)
    assert holdout_change({"x": skipped}, {"x": y}, {"x": 0.01}) == np.inf
    assert holdout_change({"x": np.full(100, np.nan)}, {"x": np.full(100, np.nan)}, {"x": 0.01}) == np.inf


def test_evidence_mostly_at_the_start_must_beat_a_restart():
    floor = {"x": 0.01}
    at_start = _fit(0.02, 0.5, start_share=0.8, evidence=1e4)
    # a start state re-estimated there explains more of it than the fit: a wrong start, not physics
    assert choose_on_training({"x": 0.2}, [at_start], floor=floor, n_train=1000, restart=lambda: 9e3) is None
    # it explains little of it: the fit stands, by how much beyond the restart recorded
    chosen = choose_on_training({"x": 0.2}, [at_start], floor=floor, n_train=1000, restart=lambda: 100.0)
    assert chosen is at_start and chosen.extra["beyond_restart"] == pytest.approx(0.8e4 - 100.0)
    assert _fit(0.02, 0.5).extra["start_share"] == 0.0     # evidence spread out: no restart asked for
    asked = []
    choose_on_training({"x": 0.2}, [_fit(0.02, 0.5)], floor=floor, n_train=1000,
                       restart=lambda: asked.append(1) or 0.0)
    assert asked == []


# -- a wrong start, or a sensor that clipped at the start ----------------------------------------

T_START = np.arange(0.0, SPAN, 1.0 / FS)
F_START = 1.0 + 0.3 * np.sin(2 * np.pi * 0.1 * T_START)     # N: the mass settles about 0.25 m, below resonance


def _start_case(x0_truth=0.0, clip_below=None, seed=3):
    """Truth positions from a start `x0_truth` m (at rest), read by a sensor with nothing below
    `clip_below` m; the model starts at rest at 0 either way."""
    rng = np.random.default_rng(seed)
    x = msd_positions(T_START, F_START, x0=(x0_truth, 0.0))
    if clip_below is not None:
        x = np.maximum(x, clip_below)
    return x + rng.normal(0.0, SIGMA, T_START.size)


def _restart_share(measured):
    """The restart's drop over the start window, as a share of the nominal's squared error there."""
    from plants import library
    from diagnosis.recording import Experiment
    from diagnosis.residuals import OutputSimulator
    from diagnosis.training_judge import restart_evidence, start_samples
    train = Experiment(T_START, {"F": F_START}, {"x": measured}, {"F": "N", "x": "m"})
    sim = OutputSimulator(library.build("mass-spring-damper"), train)
    nominal = sim()
    n = start_samples(T_START.size)
    error = float(np.sum((measured[:n] - nominal["x"][:n]) ** 2)) / SIGMA ** 2
    return restart_evidence(sim, train, nominal, {"x": SIGMA}) / error


def test_a_restart_explains_a_wrong_start_but_not_a_clipped_sensor():
    assert _restart_share(_start_case(x0_truth=0.15)) > 0.9
    assert _restart_share(_start_case(clip_below=0.08)) < 0.5


def test_a_sensor_that_clipped_only_at_the_start_is_named(tmp_path):
    x = _start_case(clip_below=0.08)
    path = tmp_path / "msd_start_clip.csv"
    path.write_text("t,F,x\n" + "\n".join(f"{a:.6f},{f:.9g},{p:.6g}" for a, f, p in zip(T_START, F_START, x)) + "\n")
    report = diagnose("mass-spring-damper", str(path), inputs=["F=F:N"], outputs=["x=x:m"], max_effects=1,
                      x0={"p_m": 0.0, "q_k": 0.0})
    (effect,) = report.to_json()["missing_physics"]
    assert (effect["kind"], effect["attached_to"], effect["judged_on"]) == ("saturation", "output x", "training")
    assert effect["parameters"]["y_min_x"] == pytest.approx(0.08, abs=2 * SIGMA)
