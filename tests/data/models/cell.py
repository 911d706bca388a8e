"""A lithium-ion cell as a user would write it (a Thevenin model without its RC pair): the open-circuit
voltage E0 + q/Cb (a linear fit of the OCV curve), the ohmic resistance R0, the charging current as
a flow source; the terminal voltage measured."""
from bondgraph.elements import C, One, R, Se, Sf
from bondgraph.graph import BondGraph


def build():
    g = BondGraph("cell", description="lithium-ion cell, open-circuit voltage and ohmic resistance")
    g.add(Sf("I", 0.0, domain="electrical", description="charging current"))
    g.add(One("cell"))
    g.connect("I", "cell")
    g.add(Se("E0", 3.3, domain="electrical", description="open-circuit voltage at empty"))
    g.connect("cell", "E0")
    g.add(C("Cb", 9000.0 / 0.8, domain="electrical", initial=4500.0, description="charge storage: 2.5 Ah over 0.8 V"))
    g.connect("cell", "Cb")
    g.add(R("R0", 0.05, domain="electrical", description="ohmic resistance"))
    g.connect("cell", "R0")
    g.add_output("V", "e_I", unit="V", description="terminal voltage")
    return g
