"""The law's sign in the feature regression (Kind.feature_signs), end to end: a force-driven carriage
pushed along its motion by a constant load and held back by a hardening spring,
``m v' = F + 1.5 N - k3 x^3`` (m = 20 kg, k3 = 0.024 N/m^3), by the tests' own RK4
(msd_truth.rk4_states), x and v measured.  The nominal (a free mass) drifts by metres: segment judge.

On this one-way motion a Coulomb friction's column is a constant load's, and the load reads as a
Coulomb level of -1.5 N (a friction that gives energy); selected beside the spring, that pair could
not be fitted with its level bound at 0, and the answer was a wrong pair (seed 4 below: end stops
and a relaxation) or ``none`` (carriage compound benchmark, seed 4302, case 014).
"""
import numpy as np
import pytest

from diagnosis.diagnose import diagnose
from diagnosis.recording import Recording
from msd_truth import rk4_states


def _recording(seed):
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, 10.0, 0.005)
    levels = rng.uniform(-10.0, 10.0, int(np.ceil(10 / 0.7)) + 1)
    F = levels[(t // 0.7).astype(int)] + 4.0 * np.sin(2 * np.pi * 0.4 * t) + 2.0

    def rate(s, f):
        return np.array([s[1], (f + 1.5 - 0.024 * s[0] ** 3) / 20.0])

    xv = rk4_states(rate, t, F, substeps=5)
    return Recording.from_arrays(t, {"F": F, "x": xv[:, 0] + rng.normal(0, 3.5e-3, t.size),
                                     "v": xv[:, 1] + rng.normal(0, 7e-4, t.size)})


@pytest.mark.parametrize("seed", [1, 4, 5])
def test_a_load_along_the_motion_and_a_hardening_spring_are_both_named(seed):
    rep = diagnose("carriage", _recording(seed), inputs=["F=F:N"], outputs=["x=x:m", "v=v:m/s"]).to_json()
    assert rep["fit"]["judge"] == "segments"
    found = {e["kind"]: e["parameters"] for e in rep["missing_physics"]}
    if "input_offset" in found:         # the force's offset is the load at its junction: one answer in two words
        found["constant_load"] = {"F0_v_cart": -found.pop("input_offset")["offset_F"]}
    assert set(found) == {"constant_load", "nonlinear_stiffness"}
    assert found["constant_load"]["F0_v_cart"] == pytest.approx(-1.5, rel=0.02)
    assert found["nonlinear_stiffness"]["k3_position"] == pytest.approx(0.024, rel=0.05)
