"""Two-mass drivetrain: motor, gearbox, compliant shaft, load (a classic servo-drive model).

Bond graph::

    Se tau_m -> 1 w_motor -> TF n -> 0 tau_shaft -> 1 dw_shaft -> C k_s, R d_s
                J_m, b_m                 |
                                         v
                                     1 w_load -> J_L, b_L, Se tau_L (braking)

* ``w_motor`` (1-junction, motor speed): rotor inertia ``J_m``, viscous
  bearing damping ``b_m`` and the motor torque ``tau_m`` (input, N m).
* ``n`` (TF, ``e1 = n e2``, ``f2 = n f1``): gearbox, ``n = w_load / w_motor``
  (a 10:1 reduction), rigid and lossless.
* ``tau_shaft`` (0-junction, shaft torque) and ``dw_shaft`` (1-junction,
  twist rate ``n w_motor - w_load``): the output shaft as a spring ``k_s``
  (state ``q_k_s``: the shaft twist, rad) parallel to a damper ``d_s``.
* ``w_load`` (1-junction, load speed): load inertia ``J_L``, viscous damping
  ``b_L`` and a load torque ``tau_L`` (input, N m; braking for ``tau_L > 0``).

Values (SI) are those of a small servo axis: the torsional resonance of the
two inertias on the shaft is ``sqrt(k_s (n^2/J_m + 1/J_L)) / (2 pi)`` =
13.3 Hz with a damping ratio of 0.065 (eigenvalues of the graph); the
rigid-body mode has a time constant ``(J_L + J_m/n^2) / (b_L + b_m/n^2)`` = 0.47 s.  Outputs ``w_m``,
``w_L`` (rad/s) and the shaft torque ``tau_s`` (N m).
"""
from __future__ import annotations

from bondgraph.elements import C, I, One, R, Se, TF, Zero
from bondgraph.graph import BondGraph
from bondgraph.params import Param

__all__ = ["drivetrain"]


def drivetrain(*, J_m: float = 2e-4, b_m: float = 1e-3, n: float = 0.1, k_s: float = 100.0,
               d_s: float = 0.1, J_L: float = 0.05, b_L: float = 0.05) -> BondGraph:
    """Motor torque on J_m, gearbox n, torsional shaft k_s || d_s, load J_L (3 states).

    Parameters (SI): ``J_m`` kg m^2, ``b_m`` N m s/rad, ``n`` (w_load/w_motor),
    ``k_s`` N m/rad, ``d_s`` N m s/rad, ``J_L`` kg m^2, ``b_L`` N m s/rad.
    States ``p_J_m``, ``q_k_s`` (shaft twist), ``p_J_L``; inputs ``tau_m``,
    ``tau_L`` (N m); outputs ``w_m``, ``w_L`` (rad/s), ``tau_s`` (N m).
    """
    rot, nms = "rotation", "N m s/rad"
    g = BondGraph("drivetrain", description="two-mass drivetrain: motor, gearbox, compliant shaft, load")
    g.add(Se("tau_m", 0.0, domain=rot, description="motor torque (input)"))
    g.add(Se("tau_L", 0.0, domain=rot, description="load torque (input, braking for tau_L > 0)"))
    for name, what in (("w_motor", "motor speed"), ("dw_shaft", "shaft twist rate n w_motor - w_load"),
                       ("w_load", "load speed")):
        g.add(One(name, description=what))
    g.add(Zero("tau_shaft", description="shaft torque"))
    g.add(I("J_m", Param("J_m", J_m, "kg m^2", "rotor inertia"), domain=rot))
    g.add(R("b_m", Param("b_m", b_m, nms, "motor bearing damping"), domain=rot))
    g.add(TF("n", Param("n", n, "1", "gear ratio w_load / w_motor")))
    g.add(C("k_s", stiffness=Param("k_s", k_s, "N m/rad", "shaft torsional stiffness"), domain=rot,
            description="shaft spring; q_k_s = twist, rad"))
    g.add(R("d_s", Param("d_s", d_s, nms, "shaft internal damping"), domain=rot))
    g.add(I("J_L", Param("J_L", J_L, "kg m^2", "load inertia"), domain=rot))
    g.add(R("b_L", Param("b_L", b_L, nms, "load viscous damping"), domain=rot))
    g.connect("tau_m", "w_motor")
    g.connect("w_motor", "J_m")
    g.connect("w_motor", "b_m")
    g.connect("w_motor", "n")
    g.connect("n", "tau_shaft")
    g.connect("tau_shaft", "dw_shaft")
    g.connect("dw_shaft", "k_s")
    g.connect("dw_shaft", "d_s")
    g.connect("tau_shaft", "w_load")
    g.connect("w_load", "J_L")
    g.connect("w_load", "b_L")
    g.connect("w_load", "tau_L")
    g.add_output("w_m", "f_J_m", unit="rad/s", description="motor speed")
    g.add_output("w_L", "f_J_L", unit="rad/s", description="load speed")
    g.add_output("tau_s", "e_k_s + e_d_s", unit="N m", description="shaft torque")
    return g
