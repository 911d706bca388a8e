"""Round 1 fits the sensors of the outputs whose residual exceeds the noise where nothing else
answers (diagnosis.diagnose): a sensor's error shows on its own output only, and graph location
may score it far below the junctions that explain the same samples through fast dynamics."""
import csv

import pytest

from diagnosis.benchmark.draw import KINDS_BEFORE_32, draw_cases
from diagnosis.benchmark.plants import PLANTS, PLANTS_BEFORE_34
from diagnosis.benchmark.run import run_case


def test_a_current_sensor_that_clips_two_brief_peaks_is_found(tmp_path):
    """Seed 2323, case 050: the dc motor's current sensor reads nothing beyond its range, reached
    by two 40 ms current peaks of the training part only.  Location scored the output at 23 % (the
    armature junction at 90 %: the electrical pole is fast), round 1 fitted the junctions' kinds
    and answered none.  Now the current sensor's range is fitted and judged on the training part,
    at the recorded extremes."""
    spec = draw_cases(80, 2323, PLANTS_BEFORE_34, KINDS_BEFORE_32)[50]
    r = run_case(spec, PLANTS, tmp_path)
    assert r["label"] == "050-dc-motor-saturation@output:i"
    assert (r["answer_kind"], r["answer_place"]) == ("saturation", "output i")
    with open(tmp_path / f"{r['label']}.csv") as f:
        current = [float(row["i"]) for row in csv.DictReader(f)]
    assert r["parameters"]["y_max_i"] == pytest.approx(max(current), abs=0.05)     # A, noise 0.005 A
    assert r["parameters"]["y_min_i"] == pytest.approx(min(current), abs=0.05)
