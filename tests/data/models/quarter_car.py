"""A quarter-car suspension as a user would write it: road velocity into a tyre spring, the
unsprung mass, a suspension spring and damper in parallel, the sprung mass."""
from bondgraph.elements import C, I, One, R, Sf, Zero
from bondgraph.graph import BondGraph


def build():
    g = BondGraph("quarter_car", description="quarter-car suspension driven by the road's vertical velocity")
    g.add(Sf("vr", 0.0, domain="translation", description="road vertical velocity"))
    g.add(Zero("tyre"))
    g.connect("vr", "tyre")
    g.add(C("kt", stiffness=160000.0, domain="translation"))
    g.connect("tyre", "kt")
    g.add(One("v_wheel"))
    g.connect("tyre", "v_wheel")
    g.add(I("mu", 35.0, domain="translation"))
    g.connect("v_wheel", "mu")
    g.add(Zero("strut"))
    g.connect("v_wheel", "strut")
    g.add(One("v_rel"))
    g.connect("strut", "v_rel")
    g.add(C("ks", stiffness=16000.0, domain="translation"))
    g.add(R("bs", 1000.0, domain="translation"))
    g.connect("v_rel", "ks")
    g.connect("v_rel", "bs")
    g.add(One("v_body"))
    g.connect("strut", "v_body")
    g.add(I("ms", 250.0, domain="translation"))
    g.connect("v_body", "ms")
    g.add_output("defl", "q_ks", unit="m", description="suspension compression")
    g.add_output("tyre_defl", "q_kt", unit="m", description="tyre compression")
    g.add_output("v_b", "f_ms", unit="m/s", description="body vertical velocity")
    return g
