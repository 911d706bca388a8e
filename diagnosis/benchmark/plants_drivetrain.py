"""Truth plants of the machine models: the two-mass drivetrain and the rigid carriage.

Hand-written in physical states (speeds, twist, position), mirroring the
library graphs ``drivetrain`` and ``carriage`` (values: their defaults).
"""
from __future__ import annotations

import numpy as np

from .plant import InputSpec, JunctionSpec, OutputSpec, StorageSpec, TruthPlant

__all__ = ["drivetrain", "carriage"]


def drivetrain() -> TruthPlant:
    """Motor ``J_m w_m' = tau_m - b_m w_m - n tau_s``, shaft ``q' = n w_m - w_L``, load
    ``J_L w_L' = tau_s - b_L w_L - tau_L`` with the shaft torque ``tau_s = k_s q + d_s q'``.

    Doors: ``w_motor`` (motor shaft), ``w_load`` (load), ``dw_shaft`` (the
    shaft's relative motion: an effort ``e`` there lowers the transmitted
    torque, ``tau_s = k_s q + d_s q' - e``); storage ``k_s`` (twist, rad).
    The shaft is compliant, so motor and load are distinct places.
    """
    J_m, b_m, n, k_s, d_s, J_L, b_L = 2e-4, 1e-3, 0.1, 100.0, 0.1, 0.05, 0.05

    def shaft(x, extra):
        w_m, q, w_L = (float(v) for v in x)
        return k_s * q + d_s * (n * w_m - w_L) - extra.get("dw_shaft", 0.0)

    def rhs(x, u, extra):
        w_m, q, w_L = (float(v) for v in x)
        tau_s = shaft(x, extra)
        return np.array([(u["tau_m"] - b_m * w_m - n * tau_s + extra.get("w_motor", 0.0)) / J_m,
                         n * w_m - w_L,
                         (tau_s - b_L * w_L - u["tau_L"] + extra.get("w_load", 0.0)) / J_L])

    def signals(x, u):
        w_m, q, w_L = (float(v) for v in x)
        return {"w_motor": w_m, "w_load": w_L, "dw_shaft": n * w_m - w_L, "k_s": q}

    rot = "rotation"
    return TruthPlant(
        name="drivetrain", model="drivetrain",
        inputs=(InputSpec("tau_m", "N m", -0.2, 0.2, 0.001, (0.05, 0.5), load_at="w_motor"),
                InputSpec("tau_L", "N m", -1.0, 1.0, 0.01, (0.5, 2.0), load_at="w_load")),
        outputs=(OutputSpec("w_m", "rad/s"), OutputSpec("w_L", "rad/s"), OutputSpec("tau_s", "N m")),
        states=("w_m", "q_shaft", "w_L"), x0=np.zeros(3), rhs=rhs, signals=signals,
        measure=lambda x, u: {"w_m": float(x[0]), "w_L": float(x[2]), "tau_s": shaft(x, {})},
        junctions=(JunctionSpec("w_motor", "1", rot), JunctionSpec("w_load", "1", rot),
                   JunctionSpec("dw_shaft", "1", rot, relative=True)),
        storages=(StorageSpec("k_s", "dw_shaft", k_s, sensed=("tau_s",)),),
        rate=1000.0, duration=10.0, substeps=4,
        description="two-mass drivetrain: motor, gearbox, compliant shaft (13 Hz), load")


def carriage() -> TruthPlant:
    """``m v' = F``, ``x' = v`` (m = 20 kg): no friction, no spring, so the nominal drifts.

    Door ``v_cart`` (the carriage's 1-junction); storage ``position`` (the
    zero-stiffness C: a spring effect there gives the carriage a restoring force).
    """
    m = 20.0

    def rhs(x, u, extra):
        return np.array([float(x[1]), (u["F"] + extra.get("v_cart", 0.0)) / m])

    return TruthPlant(
        name="carriage", model="carriage",
        inputs=(InputSpec("F", "N", -10.0, 10.0, 0.01, (0.1, 0.5), load_at="v_cart"),),
        outputs=(OutputSpec("x", "m"), OutputSpec("v", "m/s")),
        states=("x", "v"), x0=np.zeros(2), rhs=rhs,
        signals=lambda x, u: {"v_cart": float(x[1]), "position": float(x[0])},
        measure=lambda x, u: {"x": float(x[0]), "v": float(x[1])},
        junctions=(JunctionSpec("v_cart", "1", "translation"),),
        storages=(StorageSpec("position", "v_cart", 0.0),),
        rate=200.0, duration=10.0, substeps=4, drifts=True,
        description="force-driven rigid carriage (integrates its input)")
