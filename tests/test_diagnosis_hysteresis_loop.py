"""A Dahl hysteresis whose loop closes only over most of a stroke (a seal on a slow rod).

Truth: the benchmark's hand-written pneumatic-cylinder rig (F = p A + the seal's Dahl force, the
rod driven through a 37 mm triangle at 8 mm/s), with a Dahl level of 0.57 N reached over 25 mm
of travel (stiffness 22.3 N/m).  The junction's effort scale is p A, some 260 N, so a stiffness
bound read off it (two thousandths of the scale over the RMS travel: 38 N/m) excluded the truth
and the fit stopped at that bound with 47 % of the error explained.
"""
import numpy as np
import pytest

import plants
from diagnosis.benchmark.effects import make_effect
from diagnosis.benchmark.plants import PLANTS
from diagnosis.benchmark.plants_cylinder import triangle_strokes
from diagnosis.benchmark.simulate import simulate_truth
from diagnosis.catalogue import candidates
from diagnosis.fit import fit_candidate
from diagnosis.place import Place
from diagnosis.recording import Experiment

LEVEL, TRAVEL = 0.568, 0.0255          # N, m: sigma = LEVEL / TRAVEL


def test_a_dahl_loop_over_most_of_a_stroke_is_fitted():
    plant = PLANTS["pneumatic-cylinder"]()
    t = np.arange(0.0, 40.0, 1.0 / plant.rate)
    u = {"p": np.where(t < 20.0, 3e5, 5e5), "x": triangle_strokes(t, speed=0.008)}
    seal = make_effect("hysteresis", plant, "junction", "piston", LEVEL, {},
                       {"sigma": LEVEL / TRAVEL, "eps": 1.5e-4, "delta": TRAVEL})
    truth = simulate_truth(plant, t, u, seal)
    rng = np.random.default_rng(2)
    y = {"F": truth["F"] + 0.01 * rng.standard_normal(t.size), "v_piston": truth["v_piston"]}
    exp = Experiment(t, u, y, {"p": "Pa", "x": "m", "F": "N", "v_piston": "m/s"}, "seal truth")
    train, held = exp.split(0.3)
    cylinder = plants.load("pneumatic-cylinder")
    (dahl,) = [c for c in candidates(cylinder, Place("junction", "piston"), experiment=train)
               if c.kind == "hysteresis"]
    fit = fit_candidate(cylinder, dahl, train, held)
    level, stiffness = (fit.values[p.name] for p in dahl.params)
    assert level == pytest.approx(LEVEL, rel=0.03)
    assert stiffness == pytest.approx(LEVEL / TRAVEL, rel=0.05)
    # the held-out force is predicted to its noise (0.01 N)
    assert fit.holdout_nrmse["F"] < 1.2 * 0.01 / np.std(held.outputs["F"])
