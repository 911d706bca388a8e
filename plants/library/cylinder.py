"""The pneumatic-cylinder seal-friction rig as an ideal (frictionless) bond graph.

The rig (``tests/data/pneumatic_cylinder_friction/SOURCE.md``, Zillen's
3D-printed cylinder, Ø25 mm bore): the chamber is held at a constant gauge
pressure ``p`` while a linear drive moves the piston rod back and forth and a
load cell measures the rod force ``F``.  The ideal actuator gives
``F = p A`` with ``A = pi (0.0125 m)^2`` (the thesis defines friction as
``F - p A``).

Bond graph::

    Se p --> TF area (F = A p, v = Q / A) --> 1 piston --rod--> Eq servo
                                             (common velocity v)

* ``p`` (input, Pa gauge): the chamber pressure, an effort source on the
  hydraulic side (volume flow, so pressure x flow is a power).
* ``area``: a transformer with modulus ``1/A`` (``e1 = m e2``: p = F / A).
* ``piston``: the 1-junction of the piston velocity ``v`` (extension
  positive: the pressure force does positive work on the piston when it
  extends).  Seal friction, a mass or an offset act here.
* ``servo``: how the imposed motion enters.  The recording has the position
  ``x_mm`` only, so the input is the position ``x`` (m, the recording's
  coordinate, which grows on retraction: there ``F - p A > 0``, the drive
  pushes against the pressure and the seal) and the drive is a first-order
  position follower with time constant ``tau_servo``: its state ``x_s``
  follows ``x``, ``dx_s/dt = (x - x_s) / tau_servo``, and it imposes the
  piston velocity ``v = -dx_s/dt``.  With ``tau_servo = 20 ms`` (two samples
  of the 100 Hz recording) the velocity is the recorded position's
  derivative low-passed at 8 Hz: well above the 0.1 Hz strokes, and smooth
  over the laser's 0.01 mm steps.  The drive is stiff: it takes whatever
  force the junction sets, so the rod force is that effort.
* output ``F`` (N): the effort on the bond ``rod`` (piston -> servo), the
  load-cell force with the recording's sign; output ``v_piston`` (m/s) the
  piston velocity (extension positive).

With nothing else on the junction ``F = p A`` at every instant, whatever the
motion: that is the nominal model the diagnosis starts from.
"""
from __future__ import annotations

import math

from bondgraph.elements import EquationElement, MTF, One, Se
from bondgraph.graph import BondGraph
from bondgraph.params import Param
from ..errors import ArgumentError

__all__ = ["pneumatic_cylinder", "BORE_AREA"]

#: Piston area of the Ø25 mm bore, m^2.
BORE_AREA = math.pi * 0.0125 ** 2


def pneumatic_cylinder(*, area: float = BORE_AREA, tau_servo: float = 0.02) -> BondGraph:
    """Ideal pneumatic cylinder with an imposed piston position (the friction rig).

    Parameters
    ----------
    area : float, m^2
        Piston area A (default the Ø25 mm bore, ``pi * 0.0125**2``).
    tau_servo : float, s
        Time constant of the position follower that imposes the motion.

    Returns
    -------
    BondGraph
        Inputs ``p`` (Pa, gauge chamber pressure) and ``x`` (m, rod position
        as recorded); outputs ``F`` (N, rod force, ``= p A``) and ``v_piston``
        (m/s, extension positive).

    Examples
    --------
    >>> g = pneumatic_cylinder()
    >>> print(g.equations().h[0])
    A*p
    """
    for label, value in (("area", area), ("tau_servo", tau_servo)):
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
            raise ArgumentError(f"pneumatic_cylinder: {label} must be a positive number; found {value!r}")
    g = BondGraph("pneumatic_cylinder", description="ideal pneumatic cylinder F = p A, imposed rod position")
    g.add_parameter(Param("A", area, "m^2", "piston area (bore 25 mm)"))
    g.add_parameter(Param("tau_servo", tau_servo, "s", "time constant of the position follower"))
    g.add(Se("p", 0.0, domain="hydraulic", description="chamber gauge pressure"))
    g.add(MTF("area", "1/A", unit="m^-2", description="piston: p = F / A, v = Q / A"))
    g.add(One("piston", description="piston velocity (extension positive)"))
    g.add_input("x", unit="m", description="rod position as recorded (grows on retraction)")
    g.add(EquationElement(
        "servo", ports={"rod": "in"},
        outputs={"f_rod": "-(x - x_s)/tau_servo"},
        states={"x_s": "(x - x_s)/tau_servo"}, units={"x_s": "m"},
        descriptions={"x_s": "position of the drive following x"},
        description="linear drive: first-order position follower imposing the piston velocity"))
    g.connect("p", "area")
    g.connect("area", "piston")
    g.connect("piston", "servo", name="rod")
    g.add_output("F", "e_rod", unit="N", description="rod force measured by the load cell")
    g.add_output("v_piston", "f_rod", unit="m/s", description="piston velocity, extension positive")
    return g
