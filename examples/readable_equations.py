"""Readable equations: the PAM joint's ordered causal assignments, then its state equations.

The flat (fully substituted) right-hand side of a muscle pressure is thousands of characters;
the assignments name each valve's open rate and mass flow, each muscle's volume and force.

Run:  python examples/readable_equations.py [output_dir]
"""
import sys
from pathlib import Path

from plants import library
from bondgraph.assignments import substitute


def main(output_dir="."):
    out = Path(output_dir)
    out.mkdir(parents=True, exist_ok=True)
    eqs = library.build("pam").equations()
    print(eqs.pretty())                                   # assignments, then dP_1/dt = ... over them
    (out / "pam_equations.tex").write_text(eqs.latex())  # the same as a LaTeX aligned block
    flat = [len(str(f)) for f in eqs.f]
    short = [len(str(f)) for f in eqs.f_short]
    print(f"\nstate equations: {short} characters (flat: {flat}), {len(eqs.assignments)} assignments")
    # the assignments substituted back give the flat equations
    same = all(substitute(eqs.assignments, s) == f for s, f in zip(eqs.f_short, eqs.f))
    return {"names": eqs.assignment_names(), "short": short, "flat": flat, "round_trip": same}


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else ".")
