"""The machine graphs (drivetrain, carriage, hydraulic) against their hand-derived modes."""
from __future__ import annotations

import math

import numpy as np

from plants import library
from bondgraph import linearize
from plants.library.hydraulic import hydraulic_values


def _eigs(name):
    return np.linalg.eigvals(np.asarray(linearize(library.build(name).equations()).A, float))


def test_drivetrain_shaft_resonance_and_rigid_mode():
    J_m, b_m, n, k_s, J_L, b_L = 2e-4, 1e-3, 0.1, 100.0, 0.05, 0.05     # the defaults, SI
    lam = _eigs("drivetrain")
    osc = lam[np.abs(lam.imag) > 0]
    # undamped two-inertia resonance with the motor reflected through the gear
    f0 = math.sqrt(k_s * (n * n / J_m + 1.0 / J_L)) / (2 * math.pi)
    assert abs(np.abs(osc[0]) / (2 * math.pi) - f0) / f0 < 0.01           # 13.3 Hz
    real = lam[np.abs(lam.imag) == 0].real
    tau_rigid = (J_L + J_m / n ** 2) / (b_L + b_m / n ** 2)
    assert abs(-1.0 / real[0] - tau_rigid) / tau_rigid < 0.05             # 0.47 s


def test_carriage_integrates_its_input():
    assert np.allclose(_eigs("carriage"), 0.0)


def test_hydraulic_pipe_mode_and_drain_time():
    v = hydraulic_values()
    lam = _eigs("hydraulic")
    osc = lam[np.abs(lam.imag) > 0]
    Cs = v["C1"] * v["C2"] / (v["C1"] + v["C2"])
    f0 = 1.0 / (2 * math.pi * math.sqrt(v["I_pipe"] * Cs))
    assert abs(np.abs(osc[0]) / (2 * math.pi) - f0) / f0 < 0.02           # 57 Hz
    slow = lam[np.abs(lam.imag) == 0].real
    tau = (v["C1"] + v["C2"]) * v["R_out"]
    assert abs(-1.0 / slow[0] - tau) / tau < 0.05                           # 86 ms
