"""Truth plant of the hydraulic line (library ``hydraulic``), in oil volumes and pipe flow.

States: ``V1``, ``V2`` (m^3 of oil compressed into each volume; gauge
pressure ``p_i = V_i / C_i`` with ``C_i = V_i0 / beta``) and the pipe flow
``q`` (m^3/s)::

    V1' = Q_p - q,   I q' = p1 - p2 - R_pipe q,   V2' = q - p2 / R_out

Doors: 0-junctions ``p1``, ``p2`` (a flow added there: a leak ``-Q(p)`` to
the tank at gauge 0) and the 1-junction ``q_pipe`` (a pressure added along
the pipe: a turbulent loss, a check valve); storages ``C1``, ``C2`` (content:
the compressed oil volume, stiffness ``beta / V`` in Pa/m^3; ``extra["C1"]`` a pressure added to
the volume's law, a changed stiffness).
"""
from __future__ import annotations

import math

import numpy as np

from .plant import InputSpec, JunctionSpec, OutputSpec, StorageSpec, TruthPlant

__all__ = ["hydraulic"]


def hydraulic() -> TruthPlant:
    """Pump -> 1 L oil volume -> 2 m pipe (10 mm bore) -> 1 L volume -> laminar orifice to tank."""
    beta, V0, rho, mu, L, d, R_out = 1.4e9, 1e-3, 870.0, 0.04, 2.0, 0.01, 6e10   # Pa, m^3, kg/m^3, Pa s, m, m, Pa s/m^3
    C = V0 / beta                                   # m^3/Pa, each volume
    I = rho * L / (math.pi * d * d / 4.0)           # kg/m^4, oil column in the pipe
    R_pipe = 128.0 * mu * L / (math.pi * d ** 4)    # Pa s/m^3, Hagen-Poiseuille

    def rhs(x, u, extra):
        V1, V2, q = (float(v) for v in x)
        # a changed law of a volume is its pressure's (its 0-junction's effort), not a flow
        p1, p2 = V1 / C + extra.get("C1", 0.0), V2 / C + extra.get("C2", 0.0)
        return np.array([u["Q_p"] - q + extra.get("p1", 0.0),
                         q - p2 / R_out + extra.get("p2", 0.0),
                         (p1 - p2 - R_pipe * q + extra.get("q_pipe", 0.0)) / I])

    def signals(x, u):
        V1, V2, q = (float(v) for v in x)
        return {"p1": V1 / C, "p2": V2 / C, "q_pipe": q, "C1": V1, "C2": V2}

    hyd = "hydraulic"
    return TruthPlant(
        name="hydraulic", model="hydraulic",
        # pump flows 1.2-10 L/min: pressures up to ~100 bar
        inputs=(InputSpec("Q_p", "m^3/s", 2e-5, 1.67e-4, 1e-7, (0.2, 1.0), load_at="p1"),),
        outputs=(OutputSpec("p1", "Pa"), OutputSpec("p2", "Pa"), OutputSpec("q", "m^3/s")),
        states=("V1", "V2", "q"), x0=np.zeros(3), rhs=rhs, signals=signals,
        measure=lambda x, u: {"p1": float(x[0]) / C, "p2": float(x[1]) / C, "q": float(x[2])},
        junctions=(JunctionSpec("p1", "0", hyd), JunctionSpec("q_pipe", "1", hyd, one_way=True), JunctionSpec("p2", "0", hyd)),
        storages=(StorageSpec("C1", "p1", 1.0 / C, sensed=("p1",)), StorageSpec("C2", "p2", 1.0 / C, sensed=("p2",))),
        rate=1000.0, duration=5.0, substeps=4,
        description="hydraulic line: pump, volume, pipe (57 Hz oil column), volume, orifice")
