"""Each benchmark truth plant (hand-written numpy) against the library graph it mirrors.

Random zero-order-held inputs within the plant's InputSpecs drive both
``simulate_truth(plant, ...)`` and ``bondgraph.simulate`` of
``library.build(plant.model)``; every output must agree to a small fraction
of its spread.  The two codes share nothing but the equations on paper.
"""
from __future__ import annotations

import numpy as np
import pytest

from bondgraph import library, simulate
from diagnosis.benchmark.plants_exo import exoskeleton
from diagnosis.benchmark.plants_pam import PAM_PARAMS, pam, pam_frictionless
from diagnosis.benchmark.simulate import simulate_truth


def random_inputs(plant, t, seed=0):
    """Zero-order-held random levels within each InputSpec (range, quantum, hold times)."""
    rng = np.random.default_rng(seed)
    u = {}
    for spec in plant.inputs:
        values, k = np.empty(t.size), 0
        while k < t.size:
            n = max(1, int(rng.uniform(*spec.hold) * plant.rate))
            values[k:k + n] = np.round(rng.uniform(spec.low, spec.high) / spec.quantum) * spec.quantum
            k += n
        u[spec.name] = values
    return u


def parity(plant, duration, *, x0=None, seed=0, floor=None, **simulate_kw):
    """Max abs error / std of each output, truth vs bond graph (printed); `floor` per output
    bounds the std from below where an output barely moves (N m, ...)."""
    t = np.arange(int(round(duration * plant.rate)) + 1) / plant.rate
    u = random_inputs(plant, t, seed)
    truth = simulate_truth(plant, t, u)
    assert truth["_finite"]
    res = simulate(library.build(plant.model), (0.0, t[-1]), inputs={k: (t, v) for k, v in u.items()},
                   output_interval=1.0 / plant.rate, x0=x0, **simulate_kw)
    assert np.allclose(res.t, t)
    rel = {}
    for o in plant.outputs:
        err = np.max(np.abs(truth[o.name] - res[o.name]))
        scale = max(np.std(truth[o.name]), (floor or {}).get(o.name, 0.0))
        rel[o.name] = err / scale
        print(f"{plant.name}: {o.name} max|err| {err:.3g} {o.unit}, std {np.std(truth[o.name]):.3g}, "
              f"ratio {rel[o.name]:.2g}")
    return rel, truth


def _pam_x0(plant):
    psi, dpsi, P1, P2 = plant.x0
    return {"q_psi": psi, "p_J": PAM_PARAMS["J"] * dpsi, "P_1": P1, "P_2": P2}


def test_pam_equals_library_pam_with_held_kikuuwe_friction():
    # the library runs its fixed-step scheme (1 ms samples, 4 RK4 sub-steps, T_f held per sub-step)
    plant = pam()
    rel, _ = parity(plant, 1.0, x0=_pam_x0(plant))
    assert max(rel.values()) < 1e-9


def test_pam_frictionless_equals_library_and_does_not_drift():
    plant = pam_frictionless()
    assert plant.hold is None and not plant.drifts
    # same fixed-step scheme on both sides: equal to rounding
    rel, truth = parity(plant, 1.0, x0=_pam_x0(plant), method="RK4", dt=0.25e-3)
    assert max(rel.values()) < 1e-9
    # the library's adaptive solver: RK4 at 0.25 ms is within 1e-4 of the spread (tau barely moves)
    rel, truth = parity(plant, 1.0, x0=_pam_x0(plant), floor={"tau": 0.05})
    assert max(rel.values()) < 1e-3
    # restoring muscles: psi stays within the joint's range on random valve commands
    assert np.all(np.abs(truth["psi"]) < 30.0)


def test_exoskeleton_equals_library_exoskeleton():
    # stiff (d_g on J_sint: -5.1e4 1/s): LSODA per held sample vs the library's Radau
    rel, _ = parity(exoskeleton(), 2.0)
    assert max(rel.values()) < 1e-5
