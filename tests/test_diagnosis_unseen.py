"""A residual the fits never see: the truth differs from the nominal only in the held-out part.

Truth (tests/msd_truth.py): the library mass-spring-damper, its position sensor reading at most
0.3 m; the force stays small in the first 70 % of the record and grows only in the held-out
part, where the position reaches the sensor's range.  The training part holds no evidence, so
the answer is none, and the report says where the residual is and how to let the fits see it.
"""
import numpy as np
import pytest

from diagnosis.diagnose import diagnose
from msd_truth import msd_positions

FS, SPAN, SIGMA, RANGE = 50.0, 30.0, 2e-3, 0.3        # Hz, s, m, m


def test_a_residual_only_in_the_held_out_part_is_named_as_unseen(tmp_path):
    rng = np.random.default_rng(5)
    t = np.arange(0.0, SPAN, 1.0 / FS)
    amplitude = np.where(t < 0.75 * SPAN, 0.4, 2.4)                     # N: 0.1 m, then 0.6 m at rest
    force = amplitude * np.sign(np.sin(2 * np.pi * 0.2 * t))
    x = np.minimum(msd_positions(t, force), RANGE) + rng.normal(0.0, SIGMA, t.size)
    path = tmp_path / "msd_late_range.csv"
    path.write_text("t,F,x\n" + "\n".join(f"{a:.6f},{f:.9g},{p:.6g}" for a, f, p in zip(t, force, x)) + "\n")
    report = diagnose("mass-spring-damper", str(path), inputs=["F=F:N"], outputs=["x=x:m"])
    data = report.to_json()
    (effect,) = data["missing_physics"]
    assert effect["kind"] == "none"
    assert "only in the held-out part (from 21 s)" in effect["explanation"]
    assert all(a >= 21.0 for a, _ in data["location"]["windows"]) and data["location"]["windows"]
    assert "a holdout of 0.08 or less (--holdout) puts its first window, 25.5-27.54 s," in report.text
    # and with that holdout the fits see it: the sensor's range
    data = diagnose("mass-spring-damper", str(path), inputs=["F=F:N"], outputs=["x=x:m"], holdout=0.08).to_json()
    (effect,) = data["missing_physics"]
    assert (effect["kind"], effect["attached_to"]) == ("saturation", "output x")
    assert effect["parameters"]["y_max_x"] == pytest.approx(RANGE, abs=3 * SIGMA)
