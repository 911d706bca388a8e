"""End stops diagnosed end to end, from a rubber bumper as soft as the spring to a wall 100 times
stiffer: the answer names the stop, where it engages and how stiff it is.

The truth is a hand-written graph (the mass-spring-damper with an R pushing back beyond
x_b = 0.3 m), never the candidate's own build; 1 % output noise."""
import numpy as np
import pandas as pd
import pytest

import plants.library as library
from bondgraph import R
from diagnosis.diagnose import diagnose
from diagnosis.recording import Experiment
from diagnosis.residuals import OutputSimulator
from plants.library.textbook import mass_spring_damper

T = np.linspace(0.0, 20.0, 1001)                                   # 50 Hz, 20 s
F = np.where(T % 6.0 < 3.0, 2.0, -1.0) + 0.5 * np.sin(0.7 * T)   # square + sine
UNITS = {"F": "N", "x": "m", "v": "m/s"}


def _recording(path, k_b, rng):
    truth = mass_spring_damper(b=0.4)
    truth.add(R("bumper", effort="k_b*Max(q_k - x_b, 0)", params={"k_b": k_b, "x_b": 0.3}, domain="translation"))
    truth.connect("v_mass", "bumper")
    y = OutputSimulator(truth, Experiment(T, {"F": F}, {"x": T, "v": T}, UNITS))()
    noisy = {o: v + 0.01 * np.std(v) * rng.standard_normal(v.size) for o, v in y.items()}
    pd.DataFrame({"t": T, "F": F, **noisy}).to_csv(path, index=False)


@pytest.mark.parametrize("k_b, k_tol", [(2.0, 0.05), (400.0, 0.25)])
def test_an_end_stop_is_named_with_its_position_and_stiffness(tmp_path, rng, k_b, k_tol):
    path = tmp_path / "stop.csv"
    _recording(path, k_b, rng)
    report = diagnose(library.build("mass-spring-damper"), path, inputs=["F=F:N"],
                      outputs=["x=x:m", "v=v:m/s"], max_effects=1)
    data = report.to_json()
    (effect,) = data["missing_physics"]
    assert (effect["kind"], effect["attached_to"]) == ("saturation", "junction v_mass")
    values = effect["parameters"]
    assert values["q_max_k"] == pytest.approx(0.3, abs=0.01)
    assert values["k_stop_k"] == pytest.approx(k_b, rel=k_tol)
    assert min(report.improvement().values()) > 0.9          # held-out NRMSE of x and v 90 % lower
