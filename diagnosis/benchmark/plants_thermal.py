"""Truth plant of the heater pair (library ``heater-pair``), in block temperatures.

States ``T1``, ``T2`` (K)::

    C1 T1' = alpha1 Q1 + (Ta - T1)/R1 - q_link,   C2 T2' = alpha2 Q2 + (Ta - T2)/R2 + q_link,
    q_link = (T1 - T2)/R_link

Doors: the 0-junctions ``block1``, ``block2`` (a heat flow added there: a heat leak to the room at
``Ta``, a radiation loss ``-c (T^4 - Ta^4)``, a constant heat flow) and the 1-junctions ``loss1``,
``loss2`` (convection to the room) and ``link`` (between the blocks), each an R alone, so an effort
added there (a temperature difference: a series resistance, a room warmer than the model's) changes
the flow through it (``algebraic``); the losses' heat flows leave the blocks in every recording
(``one_way``: heaters only heat), the link's reverses with the hotter block.  A loss junction is
an R alone between its block and the room's fixed temperature, so an effort law there is a flow
law of the block's temperature at the block: the two are one place (``equivalent``; a constant
temperature offset on the path to the room is a constant heat flow out of the block).
"""
from __future__ import annotations

import numpy as np

from .plant import InputSpec, JunctionSpec, OutputSpec, TruthPlant

__all__ = ["heater_pair"]


def heater_pair() -> TruthPlant:
    """Two 2 J/K blocks, 1/R = 0.012 W/K each to a room at 296.15 K, 0.002 W/K between them."""
    C1 = C2 = 2.0
    R1 = R2 = 1.0 / 0.012
    R_link, alpha1, alpha2, Ta = 500.0, 0.01, 0.0075, 296.15

    def flows(x, extra):
        T1, T2 = (float(v) for v in x)
        return ((Ta - T1 + extra.get("loss1", 0.0)) / R1, (Ta - T2 + extra.get("loss2", 0.0)) / R2,
                (T1 - T2 + extra.get("link", 0.0)) / R_link)

    def rhs(x, u, extra):
        q1, q2, ql = flows(x, extra)
        return np.array([(alpha1 * u["Q1"] + q1 - ql + extra.get("block1", 0.0)) / C1,
                         (alpha2 * u["Q2"] + q2 + ql + extra.get("block2", 0.0)) / C2])

    def signals(x, u, extra=None):
        q1, q2, ql = flows(x, extra or {})
        return {"block1": float(x[0]), "block2": float(x[1]), "loss1": q1, "loss2": q2, "link": ql}

    th = "thermal"
    return TruthPlant(
        name="heater-pair", model="heater-pair",
        inputs=(InputSpec("Q1", "%", 0.0, 100.0, 0.1, (60.0, 240.0), load_at="block1"),
                InputSpec("Q2", "%", 0.0, 100.0, 0.1, (60.0, 240.0), load_at="block2")),
        outputs=(OutputSpec("T1", "K"), OutputSpec("T2", "K")),
        states=("T1", "T2"), x0=np.array([Ta, Ta]),
        nominal_x0={"q_C1": C1 * Ta, "q_C2": C2 * Ta},
        rhs=rhs, signals=signals,
        measure=lambda x, u: {"T1": float(x[0]), "T2": float(x[1])},
        junctions=(JunctionSpec("block1", "0", th, ambient=Ta, equivalent=("loss1",)),
                   JunctionSpec("block2", "0", th, ambient=Ta, equivalent=("loss2",)),
                   JunctionSpec("loss1", "1", th, algebraic=True, one_way=True, equivalent=("block1",)),
                   JunctionSpec("loss2", "1", th, algebraic=True, one_way=True, equivalent=("block2",)),
                   JunctionSpec("link", "1", th, algebraic=True)),
        rate=1.0, duration=1200.0, substeps=2,
        description="two heaters on two blocks that share heat (TCLab), absolute temperatures")
