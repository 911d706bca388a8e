"""Fitting by multiple shooting under the segment judge (diagnosis.shooting), on a plant no part
of the project was built around: a pendulum driven over the top by a piecewise-constant torque
(``tests/data/models/pendulum.py``), its truth the tests' own RK4 (``tests/msd_truth.py``) with a
concealed pivot friction.  The nominal turns a revolution behind the plant within seconds: fitted
open-loop over the training part, from the recording's first state, no friction law has a slope
to follow; fitted on restarted segments, the law's level comes out at the truth's.  (A nominal
that merely integrates, as a force-driven carriage, keeps its open-loop fits.)  A chaotic Duffing
oscillator: ``tests/test_diagnosis_duffing.py``."""
from pathlib import Path


import numpy as np
import pytest

from diagnosis.diagnose import diagnose
from diagnosis.recording import Experiment
from diagnosis.segments import Judge, plan_segments
from diagnosis.shooting import fitted_from, training_plan
from long_cases import LONG
from msd_truth import rk4_states

MODEL = Path(__file__).parent / "data" / "models" / "pendulum.py"
J, B, MGL = 0.05, 0.02, 0.49                     # kg m^2, N m s/rad, N m
FS, SPAN, SUB, AMP, NOISE = 100.0, 24.0, 10, 0.6, 0.002     # Hz, s, RK4 steps per sample, N m, rad


def _record(tmp_path, extra, seed=1):
    """A recording of the pendulum with the concealed torque `extra(w)` (N m) at the pivot."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, SPAN, 1.0 / FS)
    tau = np.repeat(rng.uniform(-AMP, AMP, t.size // 150 + 1), 150)[:t.size]

    def rate(x, u):
        return np.array([x[1], (u - B * x[1] - MGL * np.sin(x[0]) - extra(x[1])) / J])

    theta = rk4_states(rate, t, tau, substeps=SUB)[:, 0] + rng.normal(0.0, NOISE, t.size)
    assert np.ptp(theta) > 2 * np.pi               # over the top
    path = tmp_path / "pendulum.csv"
    path.write_text("t,tau,theta\n" + "\n".join(f"{a:.3f},{b:.6g},{c:.6g}" for a, b, c in zip(t, tau, theta)) + "\n")
    return path


def _diagnosis(path):
    return diagnose(str(MODEL), str(path), inputs=["tau=tau:N m"], outputs=["theta=theta:rad"], max_effects=1)


def test_the_training_part_is_cut_as_the_judge_cuts_the_held_out_part_where_the_nominal_is_unstable():
    t = np.arange(0.0, 10.0, 0.01)
    part = Experiment(t, {"u": np.zeros(t.size)}, {"y": np.zeros(t.size)}, {}, "test")
    held = Experiment(t[:300] + 10.0, {"u": np.zeros(300)}, {"y": np.zeros(300)}, {}, "test")
    judge = Judge("segments", "", held, {"y": 0.01}, plan_segments(held), mode=0.5 + 0j)   # e^1.5 over 2.99 s
    assert judge.unstable
    plan = training_plan(judge, part)
    assert (plan.length, plan.estimation) == (judge.plan.length, judge.plan.estimation) == (60, 30)
    assert plan.starts == tuple(range(0, 1000 - 59, 60)) and plan.seconds == pytest.approx(0.6)
    assert "16 segments" in fitted_from(judge, part, "the model's initial state")
    open_loop = Judge("open-loop", "", held, {"y": 0.01}, plan_segments(held))
    assert training_plan(open_loop, part) is None
    assert fitted_from(open_loop, part, "the model's initial state") == "the model's initial state"
    assert training_plan(judge, part.samples(0, 100)) is None          # fewer than two segments
    integrator = Judge("segments", "", held, {"y": 0.01}, plan_segments(held), mode=0j)      # a free mass
    assert not integrator.unstable and training_plan(integrator, part) is None


def test_coulomb_friction_on_a_pendulum_driven_over_the_top_is_found_at_its_level(tmp_path):
    report = _diagnosis(_record(tmp_path, lambda w: 0.06 * np.tanh(w / 0.01)))
    data = report.to_json()
    assert data["fit"]["judge"] == "segments" and "unstable mode" in data["fit"]["judge_reason"]
    assert "diagnosis.shooting" in data["fit"]["start"]
    (effect,) = data["missing_physics"]
    assert (effect["kind"], effect["attached_to"]) == ("coulomb_friction", "junction w")
    assert effect["parameters"]["Fc_w"] == pytest.approx(0.06, rel=0.05)
    assert data["fit"]["improved"]["theta"] < 0.1 * data["fit"]["nominal"]["theta"]


@LONG
def test_quadratic_drag_on_a_pendulum_driven_over_the_top_is_found_at_its_level(tmp_path):
    report = _diagnosis(_record(tmp_path, lambda w: 0.02 * w * abs(w)))
    data = report.to_json()
    (effect,) = data["missing_physics"]
    assert (effect["kind"], effect["attached_to"]) == ("quadratic_drag", "junction w")
    assert effect["parameters"]["c_d_w"] == pytest.approx(0.02, rel=0.03)
    assert data["fit"]["improved"]["theta"] < 0.1 * data["fit"]["nominal"]["theta"]
