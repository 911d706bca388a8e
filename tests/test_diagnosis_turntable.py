"""A load that repeats with position, on a plant no part of the project was built around: a
turntable written as a user would (``tests/data/models/turntable.py``: a 0.01 kg m^2 table on a
viscous bearing, 0.002 N m s/rad, driven by a torque, its encoder angle and its speed measured),
its truth the tests' own RK4 (``tests/msd_truth.py``), torque levels of +-0.04 N m held 1-4 s,
200 Hz for 30 s, 1 mrad and 0.01 rad/s noise: about a dozen turns either way.  An unbalance
(``m g e sin(theta + phi)``, one period per turn) and a motor's cogging (six per turn) had no
word in the vocabulary until session 36."""
from pathlib import Path

import numpy as np
import pytest

from bondgraph.numerics import simulate
from diagnosis.catalogue import candidates
from diagnosis.diagnose import diagnose
from diagnosis.kinds.periodic_load import periods
from diagnosis.place import Place
from msd_truth import rk4_states
from plants import load

MODEL = Path(__file__).parent / "data" / "models" / "turntable.py"
J, B = 0.01, 0.002          # kg m^2, N m s/rad


def _recording(path, amplitude, per_turn, seed):
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, 30.0, 0.005)
    ends = np.cumsum(rng.uniform(1.0, 4.0, 40))
    torque = rng.uniform(-0.04, 0.04, 40)[np.searchsorted(ends, t)]
    phase = rng.uniform(0.0, 2 * np.pi)

    def rate(x, tau):
        theta, w = x
        return np.array([w, (tau - B * w - amplitude * np.sin(per_turn * theta + phase)) / J])

    x = rk4_states(rate, t, torque, substeps=10)
    theta, w = x[:, 0] + rng.normal(0.0, 1e-3, t.size), x[:, 1] + rng.normal(0.0, 0.01, t.size)
    path.write_text("t,tau,theta,omega\n" + "\n".join(f"{a:.3f},{b:.6g},{c:.6g},{d:.6g}"
                                                       for a, b, c, d in zip(t, torque, theta, w)) + "\n")
    return path


def _diagnose(path):
    return diagnose(str(MODEL), str(path), inputs=["tau=tau"], outputs=["theta=theta", "omega=omega"]).to_json()


def test_the_trial_periods_repeat_twice_over_the_travel_and_are_resolved_per_sample():
    """Twice over the range, and at least four samples a period at the fastest travel."""
    theta = np.linspace(0.0, 20.0, 201)                     # 0.1 rad per sample
    trial = periods(theta, rotation=True)
    assert min(trial) >= 0.4 and max(trial) <= 10.0

    def tried(p):
        return any(abs(q - p) < 1e-9 for q in trial)
    assert tried(2 * np.pi) and tried(2 * np.pi / 8) and not tried(2 * np.pi / 16)    # 0.39 rad < 4 steps
    # a travel of 0.5 m in steps of 2.5 mm: its range over 2...32
    assert periods(np.linspace(0.0, 0.5, 201), rotation=False) == pytest.approx(
        sorted(0.5 / c for c in (2.0, 2.8, 4.0, 5.7, 8.0, 11.3, 16.0, 22.6, 32.0)))
    assert periods(np.zeros(50), rotation=False) == []


def test_a_periodic_load_repeats_with_the_travel():
    """The candidate's graph against the tests' RK4 of J w' = tau - b w - A sin(2 pi theta/P) -
    B cos(2 pi theta/P) under a constant torque."""
    table = load(str(MODEL))
    t = np.linspace(0.0, 4.0, 401)
    values = {"A_periodic_w": 0.004, "B_periodic_w": -0.002, "P_periodic_w": 1.5}
    (cand,) = [c for c in candidates(table, Place("junction", "w"), experiment=_experiment(t))
               if c.kind == "periodic_load"]
    assert [p.name for p in cand.params] == list(values) and [p.unit for p in cand.params] == ["N m", "N m", "rad"]
    run = simulate(cand.build(table, values), (0.0, 4.0), inputs={"tau": 0.03}, output_interval=0.01,
                   rtol=1e-10, atol=1e-12)

    def rate(x, tau):
        arg = 2 * np.pi * x[0] / 1.5
        return np.array([x[1], (tau - B * x[1] - 0.004 * np.sin(arg) + 0.002 * np.cos(arg)) / J])

    ref = rk4_states(rate, t, np.full(t.size, 0.03), substeps=20)
    assert run["theta"] == pytest.approx(ref[:, 0], abs=1e-6)
    assert run["omega"] == pytest.approx(ref[:, 1], abs=1e-6)
    words = cand.explain(values)
    assert "0.00447 N m" in words and "1.5 rad" in words and "4.19 per revolution" in words


def _experiment(t):
    from diagnosis.recording import Experiment
    torque = np.where(t < 2.0, 0.03, -0.03)
    theta = np.cumsum(np.full(t.size, 3.0)) * (t[1] - t[0])
    return Experiment(t, {"tau": torque}, {"theta": theta, "omega": np.full(t.size, 3.0)},
                      {"tau": "N m", "theta": "rad", "omega": "rad/s"}, "a turn")


@pytest.mark.parametrize("amplitude,per_turn,seed", [(0.01, 1, 1), (0.004, 6, 2)])
def test_an_unbalance_and_a_cogging_torque_are_periodic_loads_with_their_period(tmp_path, amplitude, per_turn,
                                                                                seed):
    data = _diagnose(_recording(tmp_path / "table.csv", amplitude, per_turn, seed))
    (effect,) = data["missing_physics"]
    assert (effect["kind"], effect["attached_to"]) == ("periodic_load", "junction w")
    fitted = effect["parameters"]
    assert fitted["P_periodic_w"] == pytest.approx(2 * np.pi / per_turn, rel=0.005)
    assert np.hypot(fitted["A_periodic_w"], fitted["B_periodic_w"]) == pytest.approx(amplitude, rel=0.03)
    assert data["fit"]["improved"]["theta"] < 0.1 * data["fit"]["nominal"]["theta"]


def test_a_turntable_without_a_load_is_answered_none(tmp_path):
    data = _diagnose(_recording(tmp_path / "table.csv", 0.0, 1, 3))
    assert [e["kind"] for e in data["missing_physics"]] == ["none"]


def test_the_features_read_the_period_off_the_estimate_on_a_fine_grid():
    """A period between two of the coarse grid's (a sinusoid at the nearer one dephases within a
    few periods of travel) is found within the fine grid's step of 0.4 %."""
    from diagnosis.kinds.periodic_load import best_periods, fine_periods

    theta = np.linspace(0.0, 3.0, 3001) ** 1.5                  # an accelerating travel, 5.2 m
    trial = periods(theta, rotation=False)
    truth = 0.37                                                # 14 periods; the grid has 0.325, 0.459
    assert min(abs(np.log(np.array(trial) / truth))) > 0.1
    estimate = 0.8 * np.sin(2 * np.pi * theta / truth + 1.0) + 0.3 + np.random.default_rng(0).normal(0, 0.2, 3001)
    best = best_periods(theta, estimate, fine_periods(trial))
    assert len(best) == 3 and min(abs(np.log(np.array(best) / truth))) < 0.004


def test_a_periodic_loads_period_is_read_off_the_models_own_travel(tmp_path):
    """Seed 4401's case 002 at --sampling 2: the cylinder's position follower (20 ms) sampled every
    14 ms has a velocity that jumps with each held sample of the commanded position, and the
    travel summed from the sampled velocity is 1.4 times the travel; the features found the seal's
    periodic load at 1.4 times its period (0.0146 m), no fit recovered from there and the answer
    was none.  The features now read the travel the model integrates (diagnosis.features)."""
    from diagnosis.benchmark.draw import KINDS, draw_cases
    from diagnosis.benchmark.plants import PLANTS
    from diagnosis.benchmark.run import run_case
    spec = draw_cases(40, 4401, PLANTS, KINDS)[2]
    r = run_case(spec, PLANTS, tmp_path, detune=0.2, sampling=2.0)
    assert r["label"] == "002-pneumatic-cylinder-periodic_load@junction:piston"
    assert r["kind_ok"] and r["place_ok"] and r["improvement"] > 0.6
    period = next(v for k, v in r["parameters"].items() if k.startswith("P_periodic"))
    assert period == pytest.approx(r["effect"]["shape"]["period"], rel=0.02)
