"""Back-support exoskeleton drive as a bond graph (Fig. 6 of [1]_).

BLDC motor -> harmonic drive -> torque sensor -> human trunk.  Inputs: the
motor torque ``tau_m`` (Se) and the trunk velocity ``w_h`` (Sf, the paper's
:math:`\\dot\\theta_h`).  Parameter values, units and their status (PAPER,
DATASHEET, PROXY, ASSUMED) come from ``docs/exo-parameters.md``; every
:class:`~bondgraph.Param` carries them in its description.

Structure (junction names are the flows / efforts they carry)::

    Se:tau_m -> 1:w_m {I:J_m, I:J_g, R:b_f}
    1:w_g {R:b_g} -> TF:r_g -> 1:w_m          (reversed TF, see below)
    1:w_g -> 0:tau_g -> 1:dw_g {C:k_g, R:d_g}
             0:tau_g -> 1:w_sint {I:J_sint} -> 0:tau_s -> 1:dw_s {C:k_s, R:d_s}
                                               0:tau_s -> 1:w_sext {I:J_sext}
    1:w_sext -> 0:tau_eh -> 1:dw_eh {C:k_eh, R:d_eh}
                0:tau_eh -> 1:w_h {R:b_h, C:theta_h}  <- Sf:w_h

Reconstruction choices (``plants/models.md`` gives the reasons):

* **Gear.** ``TF r_g`` (modulus 160, the paper's Fig. 6 label) is bonded
  with port 1 on the gear-output side and port 2 on the motor side, so
  ``w_m = r_g w_g`` and ``tau_out = r_g tau_motor`` (TF law
  ``e1 = m e2, f2 = m f1``).  The half-arrows of those two bonds point from
  the load to the motor; that is sign bookkeeping only.
* **Rigid motor/gear input.** ``J_m`` and ``J_g`` share the 1-junction
  ``w_m`` ("the shaft ... is assumed to be stiff"), so one of them is in
  derivative causality; the core eliminates it and the motor state is
  ``p_J_m`` with ``w_m = p_J_m / J_m`` and the inertia ``J_m + J_g``
  reflected into its equation.
* **Trunk.** ``Sf:w_h`` imposes the trunk velocity, so ``I:J_h`` on its
  1-junction would be in derivative causality driven by an input (its
  torque would need the derivative of ``w_h``); it only changes the torque
  the source supplies, never the states or the sensor torque, and eq. (3) of
  [1]_ drops it too.  ``J_h`` is therefore omitted; ``R:b_h`` is kept (it
  loads the source only).
* **Trunk angle.** Eq. (3) keeps the absolute trunk angle ``theta_h`` as a
  seventh state.  A zero-stiffness ``C:theta_h`` on the trunk junction
  integrates ``w_h`` into it (effort 0: no force), so the graph has the same
  seven-dimensional state space as the block diagram.

References
----------
.. [1] Exoskeleton bond graph / Kalman observer paper, seed 004 (``docs/references.md``):
   eq. (1) per-body equations, eq. (3) state matrices, Fig. 6 bond graph,
   Sec. 4 parameters, Sec. 5.1 comparison test.
"""
from __future__ import annotations

from types import MappingProxyType
from typing import Mapping

from bondgraph.elements import C, I, One, R, Se, Sf, TF, Zero
from bondgraph.graph import BondGraph
from bondgraph.params import Param, values_with_overrides

__all__ = ["exoskeleton", "PARAMETERS", "parameter_values"]

_KS = "N m s/rad"
PARAMETERS: Mapping[str, Param] = MappingProxyType({p.name: p for p in (
    Param("J_m", 3.06e-4, "kg m^2", "motor rotor inertia; DATASHEET maxon EC 90 flat 90 W, 3060 g cm^2"),
    Param("J_g", 0.413e-4, "kg m^2", "gearbox input (wave generator) inertia; PROXY size-25 SHF-2UH unit"),
    Param("b_f", 0.48e-3, _KS, "motor/gearbox friction, motor side; PAPER Sec. 4 (neglected in its "
                                "simulations, Sec. 4)"),
    Param("r_g", 160.0, "1", "gear ratio w_m / w_g; PAPER (SHD-25-160-2SH-SP)"),
    Param("b_g", 0.65, _KS, "gearbox friction, output side; PAPER Sec. 4, identified"),
    Param("k_g", 1.5e4, "N m/rad", "gearbox torsional stiffness, output side; ASSUMED (size-25 K1 region)"),
    Param("d_g", 6.0, _KS, "gearbox damping parallel to k_g; PAPER Sec. 4, identified"),
    Param("J_sint", 1.0e-4, "kg m^2", "torque-sensor inner-ring inertia; ASSUMED (~0.1 kg hub)"),
    Param("k_s", 3.0e4, "N m/rad", "torque-sensor stiffness; ASSUMED (no TS110a data)"),
    Param("d_s", 0.0, _KS, "torque-sensor damping; PAPER Sec. 4, neglected"),
    Param("J_sext", 4.0e-4, "kg m^2", "torque-sensor outer-ring inertia; ASSUMED (~0.2 kg ring)"),
    Param("k_eh", 1125.0, "N m/rad", "trunk-exoskeleton stiffness; PAPER Sec. 4 (75 kg, 1.75 m)"),
    Param("d_eh", 0.0, _KS, "trunk-exoskeleton damping; PAPER Sec. 4, neglected"),
    Param("b_h", 0.75, _KS, "hip damping; PAPER Sec. 4 (loads the Sf:w_h source only)"),
)})
"""Parameters by name (SI), with unit and source status in each description.

``J_h = 0.0491 kg m^2`` (PAPER Sec. 4) is not a parameter of the graph: with
the trunk velocity imposed it has no effect on the states (module docstring).
"""


def parameter_values(overrides: Mapping[str, float] | None = None) -> dict[str, float]:
    """Parameter values by name (SI), `overrides` applied.

    Raises
    ------
    ParameterError
        An override names no parameter (the message lists the known ones) or is not finite.
    """
    return values_with_overrides(PARAMETERS, overrides, owner="exoskeleton")


def exoskeleton(*, params: Mapping[str, float] | None = None) -> BondGraph:
    """The exoskeleton drive of Fig. 6 of [1]_ (7 states).

    Parameters
    ----------
    params : mapping str -> float, optional
        Values (SI) overriding :data:`PARAMETERS`, e.g. ``{"b_f": 0.0}`` for
        the paper's simulation setting (Sec. 4 neglects ``b_f``).

    Returns
    -------
    BondGraph
        States ``p_J_m, q_k_g, p_J_sint, q_k_s, p_J_sext, q_k_eh, q_theta_h``
        (``q_k_g = theta_m/r_g - theta_sint``, ``q_k_s = theta_sint - theta_sext``,
        ``q_k_eh = theta_sext - theta_h``, ``q_theta_h = theta_h``); inputs
        ``tau_m`` (N m), ``w_h`` (rad/s); outputs ``tau_s`` (sensor torque,
        eq. (5) ``y_t``), ``w_m`` (motor velocity, ``y_v``), ``tau_b`` (torque
        on the body, eq. (6) ``y_b``), ``theta_h``.

    Raises
    ------
    ParameterError
        An unknown name in `params`.
    """
    values = parameter_values(params)
    g = BondGraph("exoskeleton", description="back-support exoskeleton drive, Fig. 6 of the seed-004 paper")

    def p(name: str) -> Param:
        base = PARAMETERS[name]
        return Param(name, values[name], base.unit, base.description)

    def chain(*names: str) -> None:
        for tail, head in zip(names, names[1:]):
            g.connect(tail, head)

    g.add(Se("tau_m", 0.0, domain="rotation", description="motor torque, N m (input)"))
    g.add(Sf("w_h", 0.0, domain="rotation", description="trunk velocity theta_h', rad/s (input)"))
    for name in ("w_m", "w_g", "dw_g", "w_sint", "dw_s", "w_sext", "dw_eh", "w_h_j"):
        g.add(One(name))
    for name in ("tau_g", "tau_s_j", "tau_eh"):
        g.add(Zero(name))
    g.add(TF("r_g", p("r_g"), description="harmonic drive: port 1 gear output, port 2 motor side"))
    storages = [I("J_m", p("J_m"), domain="rotation"), I("J_g", p("J_g"), domain="rotation"),
                C("k_g", stiffness=p("k_g"), domain="rotation"), I("J_sint", p("J_sint"), domain="rotation"),
                C("k_s", stiffness=p("k_s"), domain="rotation"), I("J_sext", p("J_sext"), domain="rotation"),
                C("k_eh", stiffness=p("k_eh"), domain="rotation"),
                C("theta_h", law="0", state="q_theta_h", domain="rotation",
                  description="zero-stiffness angle meter: q = integral of w_h = theta_h, no torque")]
    dampers = [R(n, p(n), domain="rotation") for n in ("b_f", "b_g", "d_g", "d_s", "d_eh", "b_h")]
    for e in storages + dampers:
        g.add(e)

    chain("tau_m", "w_m")
    for e in ("J_m", "J_g", "b_f"):
        g.connect("w_m", e)
    chain("w_g", "r_g", "w_m")                  # reversed TF: w_m = r_g w_g
    g.connect("w_g", "b_g")
    # gearbox spring-damper between w_g and w_sint (flow w_g - w_sint at dw_g)
    chain("w_g", "tau_g", "dw_g", "k_g")
    g.connect("dw_g", "d_g")
    chain("tau_g", "w_sint", "J_sint")
    # torque sensor between the rings
    chain("w_sint", "tau_s_j", "dw_s", "k_s")
    g.connect("dw_s", "d_s")
    chain("tau_s_j", "w_sext", "J_sext")
    # trunk coupling and the imposed trunk velocity
    chain("w_sext", "tau_eh", "dw_eh", "k_eh")
    g.connect("dw_eh", "d_eh")
    g.connect("tau_eh", "w_h_j")
    g.connect("w_h", "w_h_j")
    g.connect("w_h_j", "b_h")
    g.connect("w_h_j", "theta_h")

    g.add_output("tau_s", "e_k_s + e_d_s", unit="N m", description="sensor torque, y_t of eq. (5)")
    g.add_output("w_m", "f_J_m", unit="rad/s", description="motor velocity, y_v of eq. (5)")
    g.add_output("tau_b", "e_k_eh + e_d_eh", unit="N m", description="torque on the body, y_b of eq. (6)")
    g.add_output("theta_h", "q_theta_h", unit="rad", description="trunk angle")
    return g
