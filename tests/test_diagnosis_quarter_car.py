"""A plant no part of the project was built around: a quarter-car suspension, written as a user
would (``tests/data/models/quarter_car.py``, a ``.py`` model file), its truth the tests' own RK4
(``tests/msd_truth.py``) on the same four states with a shock absorber that damps its rebound 2.5
times harder than its compression (1000 N s/m in compression, the nominal's; 2500 N s/m in
rebound).  Viscous friction would take the mean of the two sides; the direction-dependent law
recovers each."""
from pathlib import Path

import numpy as np
import pytest

from diagnosis.diagnose import diagnose
from msd_truth import rk4_states

MODEL = Path(__file__).parent / "data" / "models" / "quarter_car.py"
MS, MU, KS, BS, KT = 250.0, 35.0, 16000.0, 1000.0, 160000.0     # kg, kg, N/m, N s/m, N/m
FS, SPAN, SUB, REBOUND = 250.0, 12.0, 16, 1500.0                 # Hz, s, RK4 steps per sample, N s/m


def _road(t, rng):
    """Vertical road velocity (m/s): white noise through a 4 Hz first-order filter, 0.25 m/s RMS."""
    a, w, v = np.exp(-2 * np.pi * 4.0 / FS), rng.normal(0.0, 1.0, t.size), np.zeros(t.size)
    for i in range(1, t.size):
        v[i] = a * v[i - 1] + (1 - a) * w[i]
    return 0.25 * v / v.std()


def _truth(t, vr):
    """Tyre compression, wheel and body velocity, suspension compression; the road held per sample."""
    def f(x, u):
        qt, vu, qs, vb = x
        rel = vu - vb                               # > 0: the strut compresses
        force = KS * qs + (BS if rel > 0 else BS + REBOUND) * rel
        return np.array([u - vu, (KT * qt - force) / MU, rel, force / MS])
    out = rk4_states(f, t, vr, substeps=SUB, x0=np.zeros(4))
    return {"defl": out[:, 2], "tyre_defl": out[:, 0], "v_b": out[:, 3]}


def test_a_shock_absorbers_harder_rebound_is_found_on_a_user_written_quarter_car(tmp_path):
    rng = np.random.default_rng(1)
    t = np.arange(0.0, SPAN, 1.0 / FS)
    vr = _road(t, rng)
    y = {k: v + rng.normal(0.0, 0.02 * np.std(v), t.size) for k, v in _truth(t, vr).items()}
    path = tmp_path / "quarter_car.csv"
    path.write_text("t,vr,defl,tyre_defl,v_b\n" + "\n".join(
        f"{t[i]:.4f},{vr[i]:.6g},{y['defl'][i]:.6g},{y['tyre_defl'][i]:.6g},{y['v_b'][i]:.6g}"
        for i in range(t.size)) + "\n")
    report = diagnose(str(MODEL), str(path), inputs=["vr=vr:m/s"],
                      outputs=["defl=defl:m", "tyre_defl=tyre_defl:m", "v_b=v_b:m/s"], max_effects=1)
    data = report.to_json()
    (effect,) = data["missing_physics"]
    assert (effect["kind"], effect["attached_to"]) == ("asymmetric_viscous_friction", "junction v_rel")
    assert effect["parameters"]["b_fwd_v_rel"] == pytest.approx(0.0, abs=0.03 * REBOUND)
    assert effect["parameters"]["b_back_v_rel"] == pytest.approx(REBOUND, rel=0.05)
    for o in ("defl", "tyre_defl", "v_b"):
        assert data["fit"]["improved"][o] < 0.2 * data["fit"]["nominal"][o], o
