"""A turntable driven by a torque, as a user would write it: inertia J, viscous bearing b, the
angle measured by an encoder and the speed."""
from bondgraph.elements import C, I, One, R, Se
from bondgraph.graph import BondGraph


def build():
    g = BondGraph("turntable", description="turntable on a viscous bearing")
    g.add(Se("tau", 0.0, domain="rotation", description="drive torque"))
    g.add(One("w"))
    g.connect("tau", "w")
    g.add(I("J", 0.01, domain="rotation", description="table inertia"))
    g.add(R("b", 0.002, domain="rotation", description="bearing"))
    g.add(C("angle", law="0", domain="rotation", description="encoder angle (no spring)"))
    for e in ("J", "b", "angle"):
        g.connect("w", e)
    g.add_output("theta", "q_angle", unit="rad", description="angle")
    g.add_output("omega", "f_J", unit="rad/s", description="speed")
    return g
