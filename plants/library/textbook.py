"""Textbook bond graphs with known answers (each a function returning a fresh graph).

Parameter values are round numbers chosen so that the dynamics are visible
on a plot of a few seconds; every graph declares readable outputs.
"""
from __future__ import annotations

from bondgraph.elements import C, GY, I, One, R, Se, Sf, TF, Zero
from bondgraph.graph import BondGraph
from bondgraph.params import Param

__all__ = ["mass_spring_damper", "dc_motor", "rlc_series", "coupled_tanks", "geared_inertias",
           "resistor_loop"]


def _join(g: BondGraph, junction: str, *elements) -> None:
    for e in elements:
        g.add(e)
        g.connect(junction, e.name)


def mass_spring_damper(*, m: float = 1.0, b: float = 0.4, k: float = 4.0) -> BondGraph:
    """Force F on a mass m with damper b and spring k (translation).

    ``dp/dt = F - b p/m - k x``, ``dx/dt = p/m``.
    """
    g = BondGraph("mass_spring_damper", description="force on a mass with a spring and a damper")
    g.add(Se("F", 1.0, domain="translation", description="applied force"))
    g.add(One("v_mass"))
    g.connect("F", "v_mass")
    _join(g, "v_mass", I("m", m, domain="translation"), R("b", b, domain="translation"),
          C("k", stiffness=k, domain="translation"))
    g.add_output("x", "q_k", unit="m", description="spring elongation = mass position")
    g.add_output("v", "f_m", unit="m/s", description="mass velocity")
    return g


def dc_motor(*, Ra: float = 1.0, La: float = 0.5e-3, km: float = 0.05, Jm: float = 1e-4,
             bm: float = 1e-5, n: float = 0.1, bL: float = 2e-3) -> BondGraph:
    """Armature circuit -> GY (torque constant) -> rotor -> TF (gearbox, n = w_load/w_motor) -> load.

    The load side has viscous damping bL and a load torque input tau_L
    (power into the load, so it brakes for tau_L > 0).
    """
    g = BondGraph("dc_motor", description="DC motor with gearbox: voltage in, load speed out")
    g.add(Se("V", 12.0, domain="electrical", description="armature voltage"))
    g.add(One("i_arm"))
    g.connect("V", "i_arm")
    _join(g, "i_arm", R("Ra", Ra, domain="electrical"), I("La", La, domain="electrical"))
    g.add(GY("km", km, unit="N m/A", description="torque constant"))
    g.connect("i_arm", "km")
    g.add(One("w_motor"))
    g.connect("km", "w_motor")
    _join(g, "w_motor", I("Jm", Jm, domain="rotation"), R("bm", bm, domain="rotation"))
    g.add(TF("n", n, unit="1", description="gear ratio w_load / w_motor"))
    g.connect("w_motor", "n")
    g.add(One("w_load"))
    g.connect("n", "w_load")
    _join(g, "w_load", R("bL", bL, domain="rotation"), Se("tau_L", 0.0, domain="rotation",
                                                            description="load torque (braking)"))
    g.add_output("i", "f_La", unit="A", description="armature current")
    g.add_output("w_m", "f_Jm", unit="rad/s", description="motor speed")
    g.add_output("w_L", "f_bL", unit="rad/s", description="load speed")
    return g


def rlc_series(*, Rv: float = 10.0, L: float = 0.1, Cv: float = 1e-3) -> BondGraph:
    """Voltage source driving a series R, L, C loop (one current, a 1-junction)."""
    g = BondGraph("rlc_series", description="series RLC circuit driven by a voltage step")
    g.add(Se("V", 1.0, domain="electrical", description="source voltage"))
    g.add(One("i_loop"))
    g.connect("V", "i_loop")
    _join(g, "i_loop", R("Rs", Rv, domain="electrical"), I("L", L, domain="electrical"),
          C("Cs", Cv, domain="electrical"))
    g.add_output("v_C", "e_Cs", unit="V", description="capacitor voltage")
    g.add_output("i", "f_L", unit="A", description="loop current")
    return g


def coupled_tanks(*, A1: float = 0.02, A2: float = 0.02, a12: float = 5e-5, a2: float = 4e-5,
                  rho: float = 1000.0, g_acc: float = 9.81) -> BondGraph:
    """Two water tanks: inflow into tank 1, orifice 1 -> 2, orifice out of tank 2.

    Hydraulic C: ``P = rho g V / A`` (volume V, m^3).  Orifices follow
    Torricelli, ``Q = a sqrt(2 dP / rho)``, written sign-safe as
    ``a sign(dP) sqrt(2 |dP| / rho)`` (flow reverses if the pressure does).
    """
    g = BondGraph("coupled_tanks", description="two tanks with Torricelli orifices")
    for p in (Param("rho", rho, "kg/m^3", "water density"), Param("g_acc", g_acc, "m/s^2", "gravity"),
              Param("a12", a12, "m^2", "orifice area between the tanks"),
              Param("a2", a2, "m^2", "outlet orifice area of tank 2"),
              Param("A1", A1, "m^2", "cross-section of tank 1"), Param("A2", A2, "m^2", "cross-section of tank 2")):
        g.add_parameter(p)
    g.add(Sf("Q_in", 2e-4, domain="hydraulic", description="inflow into tank 1"))
    g.add(Zero("P1"))
    g.connect("Q_in", "P1")
    g.add(C("tank1", law="rho*g_acc*q/A1", domain="hydraulic", state="V1", initial=0.01))
    g.connect("P1", "tank1")
    g.add(One("Q12"))
    g.connect("P1", "Q12")
    g.add(R("orifice12", flow="a12*sign(e)*sqrt(2*Abs(e)/rho)", domain="hydraulic"))
    g.connect("Q12", "orifice12")
    g.add(Zero("P2"))
    g.connect("Q12", "P2")
    g.add(C("tank2", law="rho*g_acc*q/A2", domain="hydraulic", state="V2", initial=0.005))
    g.connect("P2", "tank2")
    g.add(R("outlet", flow="a2*sqrt(2*e/rho)", domain="hydraulic"))
    g.connect("P2", "outlet")
    g.add_output("h1", "V1/A1", unit="m", description="level in tank 1")
    g.add_output("h2", "V2/A2", unit="m", description="level in tank 2")
    g.add_output("Q_out", "f_outlet", unit="m^3/s", description="outflow")
    return g


def geared_inertias(*, J1: float = 0.01, J2: float = 0.5, n: float = 0.2, b: float = 0.05) -> BondGraph:
    """Torque on inertia J1, rigidly geared (TF n) to inertia J2: derivative causality.

    J2 is dependent storage; the reduced model has one state with the
    reflected inertia ``J1 + n^2 J2``: ``dw1/dt = (tau - b w1) / (J1 + n^2 J2)``.
    """
    g = BondGraph("geared_inertias", description="two inertias rigidly geared (derivative causality)")
    g.add(Se("tau", 1.0, domain="rotation", description="input torque"))
    g.add(One("w1"))
    g.connect("tau", "w1")
    _join(g, "w1", I("J1", J1, domain="rotation"), R("b", b, domain="rotation"))
    g.add(TF("n", n, unit="1", description="gear ratio w2 / w1"))
    g.connect("w1", "n")
    g.add(One("w2"))
    g.connect("n", "w2")
    g.add(I("J2", J2, domain="rotation"))
    g.connect("w2", "J2")
    g.add_output("w1", "f_J1", unit="rad/s", description="speed of J1")
    g.add_output("w2", "f_J2", unit="rad/s", description="speed of J2")
    return g


def resistor_loop(*, R1: float = 1.0, R2: float = 2.0, R3: float = 3.0, Cv: float = 0.5,
                  nonlinear: bool = False, a3: float = 0.5) -> BondGraph:
    """Voltage divider R1/R2 feeding R3 and a capacitor: an algebraic loop.

    With ``nonlinear=True`` R3 becomes ``e = R3 f + a3 f^3`` (not uniquely
    invertible), so the loop is solved numerically at each evaluation.
    The linear circuit is an RC with the Thevenin source
    ``V R2/(R1+R2)`` and resistance ``R1 R2/(R1+R2) + R3``.
    """
    g = BondGraph("resistor_loop" if not nonlinear else "resistor_loop_nl",
                  description="resistive divider feeding an RC branch (algebraic loop)")
    g.add(Se("V", 1.0, domain="electrical", description="source voltage"))
    g.add(One("i1"))
    g.connect("V", "i1")
    _join(g, "i1", R("R1", R1, domain="electrical"))
    g.add(Zero("v_mid"))
    g.connect("i1", "v_mid")
    _join(g, "v_mid", R("R2", R2, domain="electrical"))
    g.add(One("i3"))
    g.connect("v_mid", "i3")
    r3 = (R("R3", effort="R3v*f + a3*f**3", params={"R3v": Param("R3v", R3, "Ohm", "linear part of R3's law", min=0.0),
                                                   "a3": Param("a3", a3, "V/A^3", "cubic coefficient of R3's law")}, domain="electrical")
          if nonlinear else R("R3", R3, domain="electrical"))
    _join(g, "i3", r3, C("Cc", Cv, domain="electrical"))
    g.add_output("v_C", "e_Cc", unit="V", description="capacitor voltage")
    g.add_output("v_mid", "e_R2", unit="V", description="divider voltage")
    return g
