"""Linearise a switched model: the PAM joint at rest and at a working point.

At rest (muscles at atmospheric pressure, valves at 0 V) the valve laws sit on their kinks, so
those columns are one-sided numerical derivatives; at a working point everything is symbolic.
The output says which, per column.

Run:  python examples/linearise_switched.py [output_dir]
"""
import json
import sys
from pathlib import Path

from plants import library


def main(output_dir="."):
    out = Path(output_dir)
    out.mkdir(parents=True, exist_ok=True)
    eqs = library.build("pam-frictionless").equations()
    rest = eqs.linearize()
    working = eqs.linearize({"P_1": 3.1e5, "P_2": 2.4e5, "q_psi": 0.07, "p_J": 0.0, "u1": 6.2, "u2": 3.7})
    for label, lin in (("at rest", rest), ("working point", working)):
        print(f"--- {label}")
        print(lin)
        for name, how in lin.derivatives.items():
            print(f"  d/d{name}: {how}")
    (out / "pam_linear.json").write_text(json.dumps(working.to_dict(), indent=2))
    return {"rest": rest, "working": working}


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else ".")
