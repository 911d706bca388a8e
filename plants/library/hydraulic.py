"""A hydraulic line: pump, accumulator volume, pipe, second volume, orifice to tank.

Bond graph (gauge pressure, Pa / volume flow, m^3/s)::

    Sf Q_p -> 0 p1 -> C C1
                   -> 1 q_pipe -> I I_pipe, R R_pipe
                               -> 0 p2 -> C C2, R R_out (to tank)

* ``C1``, ``C2``: oil volumes ``V1``, ``V2`` with bulk modulus ``beta``:
  compliance ``V / beta`` (state: the volume of oil compressed in, m^3).
* ``I_pipe = rho L / a`` and ``R_pipe = 128 mu L / (pi d^4)`` (laminar,
  Hagen-Poiseuille) for a pipe of length ``L`` and bore ``d`` (``a = pi
  d^2/4``); ``R_out``: a laminar orifice (linearised restrictor) to tank.

Defaults: mineral oil (rho = 870 kg/m^3, mu = 0.04 Pa s, i.e. ISO VG 46 at
40 C, beta = 1.4e9 Pa), V1 = V2 = 1 L, a 2 m pipe of 10 mm bore, R_out = 6e10
Pa s/m^3 (10 L/min through it at 100 bar).  Then the pipe's oil column rings
on the two volumes at 1/(2 pi sqrt(I C1 C2/(C1+C2))) = 57 Hz (damping ratio
0.037) and the volumes drain through R_out with a time constant
(C1 + C2) R_out = 86 ms: both within a 1 kHz recording.
"""
from __future__ import annotations

import math

from bondgraph.elements import C, I, One, R, Sf, Zero
from bondgraph.graph import BondGraph
from bondgraph.params import Param

__all__ = ["hydraulic", "hydraulic_values"]


def hydraulic_values(*, beta=1.4e9, V1=1e-3, V2=1e-3, rho=870.0, mu=0.04, L=2.0, d=0.01, R_out=6e10):
    """Element values (SI) from the physical data: C1, C2 (m^3/Pa), I_pipe (kg/m^4), R_pipe, R_out (Pa s/m^3)."""
    a = math.pi * d * d / 4.0
    return {"C1": V1 / beta, "C2": V2 / beta, "I_pipe": rho * L / a,
            "R_pipe": 128.0 * mu * L / (math.pi * d ** 4), "R_out": R_out}


def hydraulic(**physical) -> BondGraph:
    """Pump flow ``Q_p`` (m^3/s, input) into two oil volumes joined by a pipe, orifice to tank (3 states).

    Keyword arguments are the physical data of :func:`hydraulic_values`.
    States ``q_C1``, ``q_C2`` (m^3) and ``p_I_pipe`` (pressure momentum,
    Pa s); outputs ``p1``, ``p2`` (Pa, gauge) and the pipe flow ``q`` (m^3/s).
    """
    v = hydraulic_values(**physical)
    hyd = "hydraulic"
    g = BondGraph("hydraulic", description="pump, volume, pipe (inertance, laminar loss), volume, orifice")
    g.add(Sf("Q_p", 0.0, domain=hyd, description="pump flow (input)"))
    g.add(Zero("p1", description="pressure in volume 1 (gauge)"))
    g.add(One("q_pipe", description="flow in the pipe"))
    g.add(Zero("p2", description="pressure in volume 2 (gauge)"))
    g.add(C("C1", Param("C1", v["C1"], "m^3/Pa", "volume 1 over the bulk modulus"), domain=hyd))
    g.add(C("C2", Param("C2", v["C2"], "m^3/Pa", "volume 2 over the bulk modulus"), domain=hyd))
    g.add(I("I_pipe", Param("I_pipe", v["I_pipe"], "kg/m^4", "fluid inertance rho L / a"), domain=hyd))
    g.add(R("R_pipe", Param("R_pipe", v["R_pipe"], "Pa s/m^3", "laminar pipe loss 128 mu L/(pi d^4)"),
            domain=hyd))
    g.add(R("R_out", Param("R_out", v["R_out"], "Pa s/m^3", "laminar orifice to tank"), domain=hyd))
    g.connect("Q_p", "p1")
    g.connect("p1", "C1")
    g.connect("p1", "q_pipe")
    g.connect("q_pipe", "I_pipe")
    g.connect("q_pipe", "R_pipe")
    g.connect("q_pipe", "p2")
    g.connect("p2", "C2")
    g.connect("p2", "R_out")
    g.add_output("p1", "e_C1", unit="Pa", description="gauge pressure in volume 1")
    g.add_output("p2", "e_C2", unit="Pa", description="gauge pressure in volume 2")
    g.add_output("q", "f_I_pipe", unit="m^3/s", description="pipe flow")
    return g
