"""Truth plants mirroring the library's textbook graphs (hand-written state equations).

Parameter values are the library defaults (``plants/library/textbook.py``);
the states are physical (positions, velocities, currents, volumes), not the
bond graph's momenta, so nothing here is shared with the bond-graph code.
"""
from __future__ import annotations

import numpy as np

from .plant import InductorSpec, InputSpec, JunctionSpec, OutputSpec, StorageSpec, TruthPlant

__all__ = ["mass_spring_damper", "dc_motor", "rlc", "coupled_tanks", "geared_inertias"]


def mass_spring_damper() -> TruthPlant:
    """``m x'' = F - b x' - k x`` (m = 1 kg, b = 0.4 N s/m, k = 4 N/m); x and v measured."""
    m, b, k = 1.0, 0.4, 4.0

    def rhs(x, u, extra):
        pos, vel = x
        return np.array([vel, (u["F"] - b * vel - k * pos + extra.get("v_mass", 0.0)) / m])

    return TruthPlant(
        name="msd", model="mass-spring-damper",
        inputs=(InputSpec("F", "N", -2.0, 2.0, 0.001, (0.5, 3.0), load_at="v_mass"),),
        outputs=(OutputSpec("x", "m"), OutputSpec("v", "m/s")),
        states=("x", "v"), x0=np.zeros(2), rhs=rhs,
        signals=lambda x, u: {"v_mass": x[1], "k": x[0]},
        measure=lambda x, u: {"x": x[0], "v": x[1]},
        junctions=(JunctionSpec("v_mass", "1", "translation"),),
        storages=(StorageSpec("k", "v_mass", k),),
        rate=50.0, duration=30.0, substeps=4,
        description="force on a mass with spring and damper")


def dc_motor() -> TruthPlant:
    """Armature ``L i' = V - R i - km w_m``; rotor ``Jm w_m' = km i - bm w_m - n (bL n w_m + tau_L)``.

    The gearbox is rigid (``w_L = n w_m``), so the load junction is the motor
    junction seen through the gear: the two are equivalent places.
    """
    Ra, La, km, Jm, bm, n, bL = 1.0, 0.5e-3, 0.05, 1e-4, 1e-5, 0.1, 2e-3

    def rhs(x, u, extra):
        i, w = x
        # load-side effort e_L at w_load reaches the motor shaft as n e_L (power balance)
        tau_load = n * (-bL * n * w - u["tau_L"] + extra.get("w_load", 0.0))
        return np.array([(u["V"] - Ra * i - km * w + extra.get("i_arm", 0.0)) / La,
                         (km * i - bm * w + tau_load + extra.get("w_motor", 0.0)) / Jm])

    return TruthPlant(
        name="dc-motor", model="dc-motor",
        inputs=(InputSpec("V", "V", -12.0, 12.0, 0.01, (0.1, 0.6), load_at="i_arm"),
                InputSpec("tau_L", "N m", 0.0, 0.0, 0.001, (1.0, 1.0))),
        outputs=(OutputSpec("i", "A"), OutputSpec("w_m", "rad/s"), OutputSpec("w_L", "rad/s")),
        states=("i", "w_m"), x0=np.zeros(2), rhs=rhs,
        signals=lambda x, u: {"i_arm": x[0], "w_motor": x[1], "w_load": n * x[1]},
        measure=lambda x, u: {"i": x[0], "w_m": x[1], "w_L": n * x[1]},
        junctions=(JunctionSpec("w_motor", "1", "rotation", equivalent=("w_load",)),
                   JunctionSpec("w_load", "1", "rotation", equivalent=("w_motor",)),
                   JunctionSpec("i_arm", "1", "electrical")),
        rate=1000.0, duration=6.0, substeps=8,
        description="DC motor with rigid gearbox to a damped load")


def rlc() -> TruthPlant:
    """``L i' = V - R i - q / C``, ``q' = i`` (R = 10 ohm, L = 0.1 H, C = 1 mF); a saturating
    core divides ``L`` by ``1 + extra["L"]``."""
    Rv, L, Cv = 10.0, 0.1, 1e-3

    def rhs(x, u, extra):
        i, q = x
        # a saturating core (extra["L"] = L / L_d(i) - 1) quickens the current's rate
        return np.array([(u["V"] - Rv * i - q / Cv + extra.get("i_loop", 0.0)) / L * (1.0 + extra.get("L", 0.0)), i])

    return TruthPlant(
        name="rlc", model="rlc",
        inputs=(InputSpec("V", "V", -5.0, 5.0, 0.01, (0.05, 0.3), load_at="i_loop"),),
        outputs=(OutputSpec("v_C", "V"), OutputSpec("i", "A")),
        states=("i", "q"), x0=np.zeros(2), rhs=rhs,
        signals=lambda x, u: {"i_loop": x[0], "Cs": x[1]},
        measure=lambda x, u: {"v_C": x[1] / Cv, "i": x[0]},
        junctions=(JunctionSpec("i_loop", "1", "electrical"),),
        storages=(StorageSpec("Cs", "i_loop", 1.0 / Cv, sensed=("v_C",)),),
        inductors=(InductorSpec("L", "i_loop"),),
        rate=1000.0, duration=6.0, substeps=4,
        description="series RLC circuit")


def coupled_tanks() -> TruthPlant:
    """Volumes ``V1' = Q_in - Q12``, ``V2' = Q12 - Q_out`` with Torricelli orifices.

    ``Q12 = a12 sign(dP) sqrt(2 |dP| / rho)``, ``Q_out = a2 sqrt(2 P2 / rho)``,
    ``P_i = rho g V_i / A_i`` (gauge).  Library parameters.  Like every benchmark plant the
    record starts at rest at the input's ambient value (``draw``: a delay line or a lag holds
    it before t = 0): the inflow that holds the lower level at 0.25 m,
    ``Q = a2 sqrt(2 g h2)``, with ``h1 = h2 + (Q / a12)^2 / (2 g)`` (0.41 m).  (Until session
    11 the tanks started at the library's 0.01 and 0.005 m^3 with an ambient inflow of 0, not
    at rest: a truth actuator that held 0 before t = 0 drained the tanks for the length of its
    delay, which no reading of the record as starting at rest reproduces.)
    """
    A1, A2, a12, a2, rho, g = 0.02, 0.02, 5e-5, 4e-5, 1000.0, 9.81
    h2 = 0.25
    q_rest = a2 * np.sqrt(2.0 * g * h2)
    h1 = h2 + (q_rest / a12) ** 2 / (2.0 * g)
    x0 = np.array([A1 * h1, A2 * h2])

    def pressures(x):
        return rho * g * x[0] / A1, rho * g * x[1] / A2

    def flows(x, extra):
        P1, P2 = pressures(x)
        dP = P1 - P2 + extra.get("Q12", 0.0)
        q12 = a12 * np.sign(dP) * np.sqrt(2.0 * abs(dP) / rho)
        q_out = a2 * np.sqrt(2.0 * max(P2, 0.0) / rho)
        return q12, q_out

    def rhs(x, u, extra):
        q12, q_out = flows(x, extra)
        return np.array([u["Q_in"] - q12 + extra.get("P1", 0.0),
                         q12 - q_out + extra.get("P2", 0.0)])

    def signals(x, u, extra=None):
        return dict(zip(("P1", "P2"), pressures(x))) | {"tank1": x[0], "tank2": x[1],
                                                        "Q12": flows(x, extra or {})[0]}

    def measure(x, u):
        return {"h1": x[0] / A1, "h2": x[1] / A2, "Q_out": flows(x, {})[1]}

    return TruthPlant(
        name="tanks", model="coupled-tanks",
        inputs=(InputSpec("Q_in", "m^3/s", 0.5e-4, 3.0e-4, 1e-6, (20.0, 60.0), ambient=float(q_rest),
                          load_at="P1"),),
        outputs=(OutputSpec("h1", "m"), OutputSpec("h2", "m"), OutputSpec("Q_out", "m^3/s")),
        states=("V1", "V2"), x0=x0, nominal_x0={"V1": float(x0[0]), "V2": float(x0[1])}, rhs=rhs,
        signals=signals,
        measure=measure,
        junctions=(JunctionSpec("P1", "0", "hydraulic"), JunctionSpec("P2", "0", "hydraulic"),
                   JunctionSpec("Q12", "1", "hydraulic", algebraic=True, one_way=True)),
        storages=(StorageSpec("tank1", "P1", None, content_range=(0.0, 0.03)),
                  StorageSpec("tank2", "P2", None, content_range=(0.0, 0.03))),
        rate=10.0, duration=600.0, substeps=4,
        description="two tanks with Torricelli orifices")


def geared_inertias() -> TruthPlant:
    """``(J1 + n^2 J2) w1' = tau - b w1`` (J1 = 0.01, J2 = 0.5 kg m^2, n = 0.2, b = 0.05 N m s)."""
    J1, J2, n, b = 0.01, 0.5, 0.2, 0.05

    def rhs(x, u, extra):
        w1 = x[0]
        return np.array([(u["tau"] - b * w1 + extra.get("w1", 0.0) + n * extra.get("w2", 0.0))
                         / (J1 + n * n * J2)])

    return TruthPlant(
        name="geared-inertias", model="geared-inertias",
        inputs=(InputSpec("tau", "N m", -1.0, 1.0, 0.001, (0.5, 3.0), load_at="w1"),),
        outputs=(OutputSpec("w1", "rad/s"), OutputSpec("w2", "rad/s")),
        states=("w1",), x0=np.zeros(1), rhs=rhs,
        signals=lambda x, u: {"w1": x[0], "w2": n * x[0]},
        measure=lambda x, u: {"w1": x[0], "w2": n * x[0]},
        junctions=(JunctionSpec("w1", "1", "rotation", equivalent=("w2",)),
                   JunctionSpec("w2", "1", "rotation", equivalent=("w1",))),
        rate=50.0, duration=40.0, substeps=4,
        description="two rigidly geared inertias (one degree of freedom)")
