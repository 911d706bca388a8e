"""A pendulum driven by a torque at its pivot, as a user would write it: inertia J = m l^2,
gravity's restoring torque m g l sin(theta) as a nonlinear C on the angle, a viscous pivot
damping."""
from bondgraph.elements import C, I, One, R, Se
from bondgraph.graph import BondGraph


def build():
    g = BondGraph("pendulum", description="torque-driven pendulum")
    g.add(Se("tau", 0.0, domain="rotation", description="motor torque at the pivot"))
    g.add(One("w"))
    g.connect("tau", "w")
    g.add(I("J", 0.05, domain="rotation"))
    g.add(R("b", 0.02, domain="rotation"))
    g.add(C("grav", law="mgl*sin(q)", params={"mgl": 0.49}, domain="rotation"))
    for e in ("J", "b", "grav"):
        g.connect("w", e)
    g.add_output("theta", "q_grav", unit="rad", description="pendulum angle")
    return g
