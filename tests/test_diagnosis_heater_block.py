"""A thermal plant no part of the project was built around: a heater block written as a user would
(``tests/data/models/heater_block.py``: the heater an MSf whose law ``alpha*Q`` owns its parameter,
absolute temperatures), its truth the tests' own RK4 (``tests/msd_truth.py``), 1 Hz for 30 min,
0.1 K noise and resolution.  A heater that warms up 25 s behind its command had been answered
``transport_delay``: the actuator lag could not be built on a modulated source with a parameter of
its own (it was dropped) and was counted as tried.  A thermal mass the model leaves out is heat
transfer, said in a thermal model's words.  The block's radiation had been answered as a 40 % lower
convective resistance and a sensor offset (twice the noise floor left): the vocabulary had no
fourth power, and a leak went to 0 K."""
from pathlib import Path

import numpy as np
import pytest

from diagnosis.diagnose import diagnose
from msd_truth import rk4_states

MODEL = Path(__file__).parent / "data" / "models" / "heater_block.py"
TA, CTH, UA, ALPHA = 296.15, 2.0, 0.012, 0.01          # K, J/K, W/K, W per percent
LAG, WALL_UA, WALL_C = 25.0, 0.02, 1.5                  # s; W/K and J/K of the hidden thermal mass
EPS_SIGMA_A = 0.9 * 5.67e-8 * 12e-4                     # W/K^4: emissivity 0.9 over the TCLab's 12 cm^2


def _commands(n, rng):
    """Heater levels (percent) held 60-240 s."""
    q, k, out = 0.0, 0, np.zeros(n)
    while k < n:
        hold = int(rng.uniform(60, 240))
        out[k:k + hold] = q
        k += hold
        q = float(rng.choice([0, 20, 40, 60, 80, 100]))
    return out


def _recording(path, effect, seed=1):
    rng = np.random.default_rng(seed)
    t = np.arange(1801.0)
    Q = _commands(t.size, rng)

    def rate(x, q):
        T, heat, Tw = x             # block temperature, the heater's delivered share, hidden mass
        power = ALPHA * (heat if effect == "lag" else q)
        dT = (power + UA * (TA - T) + (WALL_UA * (Tw - T) if effect == "wall" else 0.0)
              - (EPS_SIGMA_A * (T ** 4 - TA ** 4) if effect == "radiation" else 0.0)) / CTH
        return np.array([dT, (q - heat) / LAG, WALL_UA * (T - Tw) / WALL_C])

    T = rk4_states(rate, t, Q, substeps=10, x0=(TA, 0.0, TA))[:, 0]
    y = np.round((T + rng.normal(0.0, 0.1, t.size)) / 0.1) * 0.1
    path.write_text("t,Q,T\n" + "\n".join(f"{t[i]:g},{Q[i]:g},{y[i]:.1f}" for i in range(t.size)) + "\n")
    return path


def _diagnose(path):
    return diagnose(str(MODEL), str(path), inputs=["Q=Q"], outputs=["T=T:K"], max_effects=1)


def test_a_heater_that_lags_its_command_is_an_actuator_lag_a_sensor_lag_passes_for(tmp_path):
    report = _diagnose(_recording(tmp_path / "lag.csv", "lag"))
    data = report.to_json()
    (effect,) = data["missing_physics"]
    assert (effect["kind"], effect["attached_to"]) == ("valve_lag", "input Q")
    assert effect["parameters"]["tau_lag_Q"] == pytest.approx(LAG, rel=0.03)
    # one input, one output, a linear plant: a lag of the sensor gives the same record
    assert [a["kind"] for a in effect["indistinguishable"]] == ["sensor_lag"]
    assert data["fit"]["improved"]["T"] < 0.1 * data["fit"]["nominal"]["T"]


def test_a_thermal_mass_the_model_leaves_out_is_heat_transfer_at_the_block(tmp_path):
    report = _diagnose(_recording(tmp_path / "wall.csv", "wall"))
    data = report.to_json()
    (effect,) = data["missing_physics"]
    assert (effect["kind"], effect["attached_to"]) == ("heat_transfer", "junction block")
    assert "thermal mass the model leaves out" in effect["explanation"] and "gas" not in effect["explanation"]
    assert data["fit"]["improved"]["T"] < 0.1 * data["fit"]["nominal"]["T"]


def test_a_blocks_radiation_is_found_with_its_emissivity_area_product(tmp_path):
    report = _diagnose(_recording(tmp_path / "radiation.csv", "radiation"))
    data = report.to_json()
    (effect,) = data["missing_physics"]
    assert (effect["kind"], effect["attached_to"]) == ("radiation", "junction block")
    assert effect["parameters"]["c_rad_block"] == pytest.approx(EPS_SIGMA_A, rel=0.02)
    assert "296.15 K" in effect["explanation"]
    assert data["fit"]["improved"]["T"] < 0.02 * data["fit"]["nominal"]["T"]
