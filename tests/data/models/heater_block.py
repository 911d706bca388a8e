"""A heater block as a user would write it (the Temperature Control Lab's kind of rig): a heater's
power alpha*Q into a thermal capacity, convection to the ambient through a linear resistance;
absolute temperatures in K."""
from bondgraph.elements import C, MSf, One, R, Se, Zero
from bondgraph.graph import BondGraph


def build():
    g = BondGraph("heater_block", description="heater block with convective loss to the ambient")
    g.add_input("Q", default=0.0, unit="1", description="heater command, percent")
    g.add(Se("Ta", 296.15, domain="thermal", description="ambient temperature"))
    g.add(One("loss"))
    g.connect("Ta", "loss")
    g.add(R("Rc", 1 / 0.012, domain="thermal", description="convective resistance to the ambient"))
    g.connect("loss", "Rc")
    g.add(Zero("block"))
    g.connect("loss", "block")
    g.add(MSf("heater", "alpha*Q", domain="thermal", params={"alpha": 0.01}, description="heater power"))
    g.connect("heater", "block")
    g.add(C("Cth", 2.0, domain="thermal", initial=2.0 * 296.15, description="heat capacity of the block"))
    g.connect("block", "Cth")
    g.add_output("T", "q_Cth/Cth", unit="K", description="block temperature")
    return g
