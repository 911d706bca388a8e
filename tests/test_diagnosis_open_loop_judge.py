"""diagnosis.open_loop_judge: the answer it gives lists the fits of other kinds its open-loop
held-out part cannot tell apart (diagnosis.alternatives), judged on their open-loop predictions."""
from types import SimpleNamespace

import numpy as np

from diagnosis.fit import CandidateFit
from diagnosis.open_loop_judge import choose_open_loop
from diagnosis.residuals import nrmse

SIGMA = 0.02
T = np.linspace(0.0, 10.0, 4000)
TRUTH = np.sin(2 * np.pi * 0.3 * T) + 0.3 * np.sin(2 * np.pi * 1.1 * T)
MEASURED = TRUTH + np.random.default_rng(5).normal(0.0, SIGMA, T.size)


def _fit(kind, place, prediction):
    """A successful one-parameter fit whose segment reading is poor and whose open-loop
    held-out prediction is `prediction`."""
    return CandidateFit(SimpleNamespace(kind=kind, place=place), {}, {"v": 0.05}, {"v": 0.08}, 1, True, "",
                        extra={"open_loop": {"v": nrmse(MEASURED, prediction)}, "open_loop_y": {"v": prediction}})


def test_the_open_loop_answer_lists_the_fits_it_cannot_tell_apart():
    """A constant load and a sensor offset that predict the force alike (0.1 noise sigma apart) are
    listed with whichever is chosen; a fit 3 sigma off everywhere is resolved and is not."""
    load = _fit("constant_load", "junction piston", TRUTH)
    offset = _fit("sensor_offset", "output F", TRUTH + 0.1 * SIGMA)
    biased = _fit("viscous_friction", "junction piston", TRUTH + 3.0 * SIGMA)
    floor = {"v": SIGMA / np.std(MEASURED)}
    chosen, alternatives = choose_open_loop({"v": 1.5}, floor, [offset, biased, load], measured={"v": MEASURED})
    assert chosen in (load, offset) and chosen.extra["judge"] == "open-loop"
    other = offset if chosen is load else load
    assert [(a.kind, a.place) for a in alternatives] == [(other.candidate.kind, other.candidate.place)]
    assert alternatives[0].z < 3.0 and alternatives[0].difference <= 0.11   # in noise sigmas


def test_no_open_loop_answer_lists_nothing():
    far = _fit("constant_load", "junction piston", TRUTH + 10.0 * SIGMA)
    floor = {"v": SIGMA / np.std(MEASURED)}
    assert choose_open_loop({"v": 1.5}, floor, [far], measured={"v": MEASURED}) == (None, [])
