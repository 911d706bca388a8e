"""Quick start: a mass-spring-damper as a bond graph, from equations to a plot.

Run:  python examples/quickstart.py [output_dir]
"""
import sys
from pathlib import Path

from bondgraph import BondGraph, C, I, One, R, Se
from bondgraph.io_json import save
from bondgraph.numerics import simulate


def build() -> BondGraph:
    """Force F on mass m with damper b and spring k (power flows from F into the junction)."""
    g = BondGraph("quickstart_msd", description="mass-spring-damper")
    g.add(Se("F", 1.0, domain="translation"))
    g.add(One("v"))
    g.add(I("m", 1.0, domain="translation"))
    g.add(R("b", 0.4, domain="translation"))
    g.add(C("k", stiffness=4.0, domain="translation"))
    g.connect("F", "v")
    for element in ("m", "b", "k"):
        g.connect("v", element)
    g.add_output("x", "q_k", unit="m", description="position")
    return g


def main(output_dir="."):
    out = Path(output_dir)
    out.mkdir(parents=True, exist_ok=True)
    graph = build()
    eqs = graph.equations()
    print(eqs)                                    # explicit state equations with units
    lin = eqs.linearize()                         # named A, B, C, D
    omega, magnitude, phase = lin.bode("F", "x")
    peak = omega[magnitude.argmax()]
    print(f"resonance of F -> x near {peak:.2f} rad/s (undamped: 2 rad/s)")
    result = simulate(graph, (0.0, 20.0), inputs={"F": "Heaviside(t - 1)"}, output_interval=0.01)
    result.to_csv(out / "quickstart.csv")
    result.plot(["x"]).savefig(out / "quickstart.png", dpi=120)
    graph.draw(out / "quickstart_graph.png")
    save(graph, out / "quickstart_graph.json")
    return result


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else ".")
