"""A pseudo-bond graph: a valve filling a pneumatic cylinder that pushes a mass.

The chamber is an equation-defined element with a pressure / mass-flow port
(pneumatic) and a force / velocity port (mechanical):

    dP/dt = kappa R T mdot / V - kappa P (dV/dt) / V,   V = Ap x,   F = (P - Pa) Ap

Run:  python examples/pneumatic_cylinder.py [output_dir]
"""
import sys
from pathlib import Path

from bondgraph import BondGraph, C, EquationElement, I, MSf, One, R
from bondgraph.numerics import simulate


def build() -> BondGraph:
    g = BondGraph("pneumatic_cylinder", description="valve -> chamber -> piston mass with a return spring")
    g.add_input("u", default=1.0, unit="", description="valve opening 0..1")
    g.add(MSf("valve", "u*kv*(Ps - P)", params={"kv": 2e-8, "Ps": 6e5}, domain="pneumatic"))
    g.add(EquationElement(
        "chamber", ports={"pn": "in", "mech": "out"},
        outputs={"e_pn": "P", "e_mech": "(P - Pa)*Ap"},
        states={"P": "kappa*Rg*T*f_pn/(Ap*x) - kappa*P*f_mech/x", "x": "f_mech"},
        initial={"P": 1.013e5, "x": 0.01}, units={"P": "Pa", "x": "m"},
        descriptions={"P": "chamber pressure (absolute)", "x": "piston stroke"},
        params={"kappa": 1.4, "Rg": 287.0, "T": 293.0, "Ap": 4.9e-4, "Pa": 1.013e5}))
    g.connect("valve", ("chamber", "pn"))
    g.add(One("piston"))
    g.connect(("chamber", "mech"), "piston")
    for element in (I("mp", 0.8, domain="translation"), R("seal", 40.0, domain="translation"),
                    C("spring", stiffness=2000.0, domain="translation")):
        g.add(element)
        g.connect("piston", element.name)
    g.add_output("P_kPa", "P/1000", unit="kPa")
    g.add_output("stroke", "x", unit="m")
    return g


def main(output_dir="."):
    out = Path(output_dir)
    out.mkdir(parents=True, exist_ok=True)
    graph = build()
    print(graph.equations())
    result = simulate(graph, (0.0, 1.0), output_interval=1e-3)
    result.plot(["P_kPa", "stroke"]).savefig(out / "pneumatic_cylinder.png", dpi=120)
    graph.draw(out / "pneumatic_cylinder_graph.png")
    print(f"final pressure {result['P_kPa'][-1]:.1f} kPa, stroke {result['stroke'][-1] * 1000:.1f} mm")
    return result


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else ".")
