"""A double-well Duffing oscillator driven by a force, as a user would write it: mass m, damping
b, a spring whose force k3 q^3 - k1 q has two wells (an unstable equilibrium at 0)."""
from bondgraph.elements import C, I, One, R, Se
from bondgraph.graph import BondGraph


def build():
    g = BondGraph("duffing", description="double-well Duffing oscillator")
    g.add(Se("F", 0.0, domain="translation", description="drive force"))
    g.add(One("v"))
    g.connect("F", "v")
    g.add(I("m", 1.0, domain="translation"))
    g.add(R("b", 0.3, domain="translation"))
    g.add(C("k", law="k3*q**3 - k1*q", params={"k1": 1.0, "k3": 1.0}, domain="translation"))
    for e in ("m", "b", "k"):
        g.connect("v", e)
    g.add_output("x", "q_k", unit="m", description="position")
    return g
