"""Truth plant of the pneumatic-cylinder seal-friction rig (library ``pneumatic-cylinder``).

The rig holds the chamber at a gauge pressure ``p`` while a linear drive
moves the rod and a load cell measures the rod force ``F``.  The nominal
actuator is ideal: ``F = p A`` with ``A = pi (0.0125 m)^2`` (Ø25 mm bore).
The drive is a first-order position follower, state ``x_s`` (m):
``dx_s/dt = (x - x_s) / tau_servo`` with ``tau_servo = 20 ms``, imposing the
piston velocity ``v = -dx_s/dt`` (extension positive; the recorded position
``x`` grows on retraction).

Effect door: the 1-junction ``piston`` (velocity ``v``, signal ``p`` for a
pressure-dependent seal friction).  The piston is massless, so an effort
``e`` added there goes straight into the rod force: ``F = p A + e``
(seal friction ``e = -F_f(v, p)``: ``F - p A > 0`` on retraction, as the
rig's thesis defines friction).  Hence ``feedthrough=True``.

Excitation: the real rig strokes ~37 mm at ~6-11 mm/s with the pressure
held per file (1, 3, 5, 7 bar).  The position input is therefore drawn as
:func:`triangle_strokes` at a random 5-12 mm/s (its ``profile``), not as
random held levels, which the follower would turn into 20 ms step strokes.
"""
from __future__ import annotations

import math

import numpy as np

from .plant import InputSpec, JunctionSpec, OutputSpec, TruthPlant

__all__ = ["pneumatic_cylinder", "switched_cylinder", "triangle_strokes", "AREA", "TAU_SERVO"]

AREA = math.pi * 0.0125 ** 2     # m^2, piston area of the Ø25 mm bore
TAU_SERVO = 0.02                 # s, time constant of the drive's position follower


def triangle_strokes(t, *, stroke: float = 0.037, speed: float = 0.008, x_min: float = 0.0):
    """Rod position of back-and-forth strokes at constant speed, m (a triangle wave).

    t : ndarray, s; stroke : m; speed : m/s; x_min : m (start of the stroke).
    """
    period = 2.0 * stroke / speed
    phase = np.mod(np.asarray(t, float), period) / period
    return x_min + stroke * (1.0 - np.abs(2.0 * phase - 1.0))


def pneumatic_cylinder() -> TruthPlant:
    """Ideal cylinder F = p A with a first-order position follower imposing the motion (1 state)."""

    def velocity(x, u):
        return -(u["x"] - float(x[0])) / TAU_SERVO      # m/s, extension positive

    def rhs(x, u, extra):
        # the drive is stiff: it imposes the velocity whatever force the junction sets,
        # so nothing at the piston changes the state
        return np.array([(u["x"] - float(x[0])) / TAU_SERVO])

    def measure(x, u, extra):
        return {"F": u["p"] * AREA + extra.get("piston", 0.0), "v_piston": velocity(x, u)}

    return TruthPlant(
        name="pneumatic-cylinder", model="pneumatic-cylinder",
        inputs=(InputSpec("p", "Pa", 1.0e5, 7.0e5, 1.0e3, (20.0, 40.0)),
                InputSpec("x", "m", 0.0, 0.037, 1.0e-5, (2.0, 6.0),
                          profile=lambda t, rng: triangle_strokes(t, speed=float(rng.uniform(0.005, 0.012))))),
        outputs=(OutputSpec("F", "N"), OutputSpec("v_piston", "m/s")),
        states=("x_s",), x0=np.zeros(1), rhs=rhs,
        signals=lambda x, u: {"piston": velocity(x, u), "p": u["p"]},
        measure=measure,
        junctions=(JunctionSpec("piston", "1", "translation", pressures=("p",)),),
        rate=100.0, duration=80.0, substeps=4, feedthrough=True,
        description="pneumatic cylinder seal-friction rig: F = p A, imposed rod position")


def switched_cylinder() -> TruthPlant:
    """The same rig with the chamber pressure switched every 0.5-3 s while the rod strokes.

    A command that changes often and sets a friction level through a lag is the
    structure of a magnetorheological damper (force against an imposed motion, the
    yield level following the coil voltage through the coil's lag): the piston
    junction lists ``p`` as a modulator (``modulated_friction``).  Equations, states
    and nominal model are those of :func:`pneumatic_cylinder`.
    """
    from dataclasses import replace

    base = pneumatic_cylinder()
    p, x = base.inputs
    return replace(base, name="switched-cylinder", duration=40.0,
                   inputs=(replace(p, hold=(0.5, 3.0)), x),
                   junctions=(JunctionSpec("piston", "1", "translation", pressures=("p",), modulators=("p",)),),
                   description="pneumatic cylinder rig, pressure switched every 0.5-3 s: F = p A, imposed rod")
