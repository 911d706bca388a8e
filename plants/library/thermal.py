"""Two heaters on two aluminium blocks that share heat: the Temperature Control Lab's kind of rig.

Bond graph (absolute temperature, K / heat flow, W)::

    MSf heater1 -> 0 block1 -> C C1        Se Ta -> 0 room -> 1 loss1 -> R R1, 0 block1
    MSf heater2 -> 0 block2 -> C C2                         -> 1 loss2 -> R R2, 0 block2
                   0 block1 -> 1 link -> R R_link, 0 block2

* ``heater_i``: power ``alpha_i Q_i`` (W) for a command ``Q_i`` in percent (inputs);
* ``C_i``: the block's heat capacity ``m c_p`` (J/K), state the heat it holds, ``q = C T`` (J),
  starting at the ambient's temperature;
* ``R_i``: convection to the room (the effort source ``Ta``, K: an input, by default constant),
  ``1/(U A)`` (K/W);
* ``R_link``: the heat the blocks exchange (conduction through the board), ``1/(U A_s)``.

Defaults (the TCLab's published data): ``m = 4 g`` of aluminium (``c_p = 500 J/(kg K)``: C = 2 J/K),
``U = 10 W/(m^2 K)``, ``A = 12 cm^2`` (R = 83.3 K/W), ``A_s = 2 cm^2`` between the blocks
(R_link = 500 K/W), ``alpha_1 = 0.01`` and ``alpha_2 = 0.0075 W`` per percent, ambient 23 C.  Each
block settles with a time constant of about ``C R = 140-170 s``.  Radiation (``eps sigma A (T^4 -
Ta^4)``), which the published model has besides, is left out: it is what a diagnosis may find.
"""
from __future__ import annotations

from bondgraph.elements import C, MSf, One, R, Se, Zero
from bondgraph.graph import BondGraph
from bondgraph.params import Param

__all__ = ["heater_pair"]

T_AMBIENT = 296.15   # K


def heater_pair(*, C1=2.0, C2=2.0, R1=1 / 0.012, R2=1 / 0.012, R_link=500.0, alpha1=0.01, alpha2=0.0075,
                Ta=T_AMBIENT) -> BondGraph:
    """Heater commands ``Q1``, ``Q2`` (percent, inputs; the ambient ``Ta``, K, a third) into two
    blocks losing heat to the ambient and sharing it (2 states ``q_C1``, ``q_C2``, J); outputs the
    block temperatures ``T1``, ``T2`` (K)."""
    th = "thermal"
    g = BondGraph("heater_pair", description="two heaters on two blocks that share heat (TCLab)")
    for i, alpha in ((1, alpha1), (2, alpha2)):
        g.add_input(f"Q{i}", default=0.0, unit="%", description=f"heater {i} command")
        g.add(MSf(f"heater{i}", f"alpha{i}*Q{i}", domain=th,
                  params={f"alpha{i}": Param(f"alpha{i}", alpha, "W/%", f"heater {i} power per percent")},
                  description=f"heater {i} power"))
        g.add(Zero(f"block{i}", description=f"temperature of block {i}"))
        g.add(One(f"loss{i}", description=f"convection from block {i} to the ambient"))
    g.add(Se("Ta", Ta, domain=th, description="ambient temperature"))
    g.add(Zero("room", description="the ambient both blocks lose heat to"))
    g.connect("Ta", "room")
    g.add(C("C1", Param("C1", C1, "J/K", "heat capacity of block 1"), domain=th, initial=C1 * Ta))
    g.add(C("C2", Param("C2", C2, "J/K", "heat capacity of block 2"), domain=th, initial=C2 * Ta))
    g.add(R("R1", Param("R1", R1, "K/W", "convective resistance of block 1"), domain=th))
    g.add(R("R2", Param("R2", R2, "K/W", "convective resistance of block 2"), domain=th))
    g.add(One("link", description="heat exchanged between the blocks"))
    g.add(R("R_link", Param("R_link", R_link, "K/W", "thermal resistance between the blocks"), domain=th))
    for i in (1, 2):
        g.connect(f"heater{i}", f"block{i}")
        g.connect(f"block{i}", f"C{i}")
        g.connect("room", f"loss{i}")
        g.connect(f"loss{i}", f"R{i}")
        g.connect(f"loss{i}", f"block{i}")
    g.connect("block1", "link")
    g.connect("link", "R_link")
    g.connect("link", "block2")
    g.add_output("T1", "e_C1", unit="K", description="temperature of block 1")
    g.add_output("T2", "e_C2", unit="K", description="temperature of block 2")
    return g
