"""Truth plant of the back-support exoskeleton drive (seed 004), hand-written in physical states.

Rodrigues-Carvalho et al.'s exoskeleton drive (seed 004: BLDC motor ->
harmonic drive -> torque sensor -> human trunk), eq. (1) with the gear
friction as in the matrix eq. (3) (``b_g / r_g^2`` at the motor: R:b_g sits
on the gear-output junction, plants/models.md) and the project's parameter
sheet (``exo-parameters.md``; ``b_f`` kept at its PAPER value as in the
library graph).  States (eq. (2)):
``x = (theta_m, w_m, theta_sint, w_sint, theta_sext, w_sext, theta_h)``
(rad, rad/s); inputs ``tau_m`` (N m) and ``w_h`` (rad/s, imposed trunk
velocity); outputs eqs. (5)-(6): ``tau_s`` (sensor torque, N m), ``w_m``
(rad/s), ``tau_b`` (torque on the body, N m), ``theta_h`` (rad).

Effect doors (nominal graph names):

* 1-junctions of absolute velocity: ``w_m`` (motor shaft, J_m + J_g),
  ``w_g`` (gear output, ``w_m / r_g``; rigidly geared to ``w_m``, so the two
  are equivalent places: a torque ``e`` at ``w_g`` reaches the motor as
  ``e / r_g``), ``w_sint`` (sensor inner ring), ``w_sext`` (outer ring);
* 1-junctions of relative velocity, where the spring-damper pairs sit:
  ``dw_g`` (gear twist rate ``w_g - w_sint``), ``dw_s`` (sensor), ``dw_eh``
  (trunk coupling).  An effort ``e`` INTO ``dw_g`` lowers the torque the
  pair transmits: ``tau_g = k_g q_g + d_g dq_g - e`` (friction there is
  ``e = -F(dq_g)``, it stiffens the coupling);
* storages ``k_g``, ``k_s``, ``k_eh`` (content: the twist, rad).

The trunk junction ``w_h_j`` is not a door: its velocity is imposed, so a
torque there changes nothing but the source's torque.

The drive is stiff (eigenvalues down to -5.1e4 1/s: d_g on J_sint), so the
plant is integrated with LSODA, one restart per sample of the held inputs.
"""
from __future__ import annotations

import math

import numpy as np

from .plant import InputSpec, JunctionSpec, OutputSpec, StorageSpec, TruthPlant

__all__ = ["exoskeleton", "EXO_PARAMS"]

#: Parameter sheet of the seed-004 drive, SI (N m s/rad, N m/rad, kg m^2).
EXO_PARAMS = dict(J_m=3.06e-4, J_g=0.413e-4, b_f=0.48e-3, r_g=160.0, b_g=0.65, k_g=1.5e4, d_g=6.0,
                  J_sint=1.0e-4, k_s=3.0e4, d_s=0.0, J_sext=4.0e-4, k_eh=1125.0, d_eh=0.0)


def exoskeleton() -> TruthPlant:
    """The seed-004 drive, eq. (1) of the paper in its 7 physical states (library ``exoskeleton``)."""
    p = EXO_PARAMS
    J1 = p["J_m"] + p["J_g"]                # rigid motor shaft: rotor and wave generator, eq. (1)
    r = p["r_g"]

    def couplings(x, u, extra):
        """Torques transmitted by the gear, the sensor and the trunk coupling, N m."""
        th_m, w_m, th_i, w_i, th_e, w_e, th_h = (float(v) for v in x)
        tau_g = p["k_g"] * (th_m / r - th_i) + p["d_g"] * (w_m / r - w_i) - extra.get("dw_g", 0.0)
        tau_s = p["k_s"] * (th_i - th_e) + p["d_s"] * (w_i - w_e) - extra.get("dw_s", 0.0)
        tau_b = p["k_eh"] * (th_e - th_h) + p["d_eh"] * (w_e - u["w_h"]) - extra.get("dw_eh", 0.0)
        return tau_g, tau_s, tau_b

    def rhs(x, u, extra):
        w_m, w_i, w_e = float(x[1]), float(x[3]), float(x[5])
        tau_g, tau_s, tau_b = couplings(x, u, extra)
        # gear output junction w_g = w_m / r: b_g, the gear spring-damper and any added torque,
        # reflected to the motor through the TF (divided by r)
        gear_out = -p["b_g"] * w_m / r - tau_g + extra.get("w_g", 0.0)
        dw_m = (u["tau_m"] - p["b_f"] * w_m + extra.get("w_m", 0.0) + gear_out / r) / J1
        dw_i = (tau_g - tau_s + extra.get("w_sint", 0.0)) / p["J_sint"]
        dw_e = (tau_s - tau_b + extra.get("w_sext", 0.0)) / p["J_sext"]
        return np.array([w_m, dw_m, w_i, dw_i, w_e, dw_e, u["w_h"]])

    def signals(x, u):
        th_m, w_m, th_i, w_i, th_e, w_e, th_h = (float(v) for v in x)
        return {"w_m": w_m, "w_g": w_m / r, "w_sint": w_i, "w_sext": w_e,
                "dw_g": w_m / r - w_i, "dw_s": w_i - w_e, "dw_eh": w_e - u["w_h"],
                "k_g": th_m / r - th_i, "k_s": th_i - th_e, "k_eh": th_e - th_h}

    def measure(x, u):
        _, tau_s, tau_b = couplings(x, u, {})
        return {"tau_s": tau_s, "w_m": float(x[1]), "tau_b": tau_b, "theta_h": float(x[6])}

    rot = "rotation"
    return TruthPlant(
        name="exoskeleton", model="exoskeleton",
        # as the cases drive it: motor torque levels +-0.2 N m (32 N m at the gear output), trunk
        # flexion phases +-0.4 rad/s held 1-2.5 s
        inputs=(InputSpec("tau_m", "N m", -0.2, 0.2, 0.001, (0.05, 0.3), load_at="w_m"),
                InputSpec("w_h", "rad/s", -0.4, 0.4, math.radians(0.1), (1.0, 2.5))),
        outputs=(OutputSpec("tau_s", "N m"), OutputSpec("w_m", "rad/s"), OutputSpec("tau_b", "N m"),
                 OutputSpec("theta_h", "rad")),
        states=("theta_m", "w_m", "theta_sint", "w_sint", "theta_sext", "w_sext", "theta_h"),
        x0=np.zeros(7), rhs=rhs, signals=signals, measure=measure,
        junctions=(JunctionSpec("w_m", "1", rot, equivalent=("w_g",)),
                   JunctionSpec("w_g", "1", rot, equivalent=("w_m",)),
                   JunctionSpec("w_sint", "1", rot), JunctionSpec("w_sext", "1", rot),
                   JunctionSpec("dw_g", "1", rot, relative=True), JunctionSpec("dw_s", "1", rot, relative=True),
                   JunctionSpec("dw_eh", "1", rot, relative=True)),
        storages=(StorageSpec("k_g", "dw_g", p["k_g"]), StorageSpec("k_s", "dw_s", p["k_s"], sensed=("tau_s",)),
                  StorageSpec("k_eh", "dw_eh", p["k_eh"], sensed=("tau_b",))),
        rate=200.0, duration=10.0, method="lsoda",
        description="back-support exoskeleton drive, seed 004 (stiff: LSODA)")
