"""What a notebook shows: a BondGraph as its drawing (SVG), StateEquations as LaTeX.

In Jupyter, evaluating ``graph`` or ``graph.equations()`` in a cell displays these.

Run:  python examples/notebook_display.py [output_dir]
"""
import sys
from pathlib import Path

from plants import library


def main(output_dir="."):
    out = Path(output_dir)
    out.mkdir(parents=True, exist_ok=True)
    graph = library.build("dc-motor")
    svg = graph._repr_svg_()
    latex = graph.equations()._repr_latex_()
    (out / "dc_motor.svg").write_text(svg)
    (out / "dc_motor_equations.tex").write_text(latex)
    print(latex)
    lin = graph.equations().linearize()
    sys_ = lin.to_control()                         # python-control StateSpace, for its tools
    print(sys_)
    return {"svg": svg, "latex": latex, "control": sys_}


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else ".")
