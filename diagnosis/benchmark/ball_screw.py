"""``python -m diagnosis.benchmark.ball_screw [--cases N] [--seed S] [--dir DIR]``: the issue's ball-screw shape.

A rig's axis rarely misses one thing: the ball-screw axis of issue 11 lacked viscous and Coulomb
friction and a constant force offset at once.  The compound benchmark (:mod:`diagnosis.benchmark.compound`)
draws a second effect of any kind; this set conceals exactly that shape, a Coulomb + viscous friction and
a constant load at one mechanical 1-junction, on the carriage, the mass-spring, the geared pair, the DC
motor and the drivetrain in turn, with each effect's change of the output (5-30 % of its spread), its
effect-to-noise ratio (3-30, log-uniform) and the excitation drawn per case.  It is a measurement (docs:
"Session 40" of ``docs/diagnosis.md``), not a set anything was tuned on.  Prints one line per case and
how often some answer names each effect and both.
"""
from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np

from .draw import CaseSpec

#: (plant, mechanical 1-junction) in turn
PLACES = (("carriage", "v_cart"), ("msd", "v_mass"), ("geared-inertias", "w2"), ("dc-motor", "w_load"),
          ("drivetrain", "w_load"))
EXCITATIONS = ("levels", "prbs", "levels+sine")


def cases(n: int, seed: int) -> list[tuple[CaseSpec, CaseSpec]]:
    """`n` pairs ``(friction, load)`` of case specs: the Coulomb + viscous friction first, the constant
    load second, at one junction, drawn from ``numpy.random.default_rng(seed)``.

    >>> [(a.plant, a.name, b.kind) for a, b in cases(2, 11)]
    [('carriage', 'v_cart', 'constant_load'), ('msd', 'v_mass', 'constant_load')]
    """
    rng = np.random.default_rng(seed)
    out = []
    for i in range(n):
        plant, junction = PLACES[i % len(PLACES)]
        case_seed = int(rng.integers(1 << 30))
        excitation = EXCITATIONS[int(rng.integers(len(EXCITATIONS)))]

        def drawn(kind, s):
            change, ratio = float(rng.uniform(0.05, 0.3)), float(np.exp(rng.uniform(np.log(3), np.log(30))))
            return CaseSpec(i, s, plant, kind, "junction", junction, change, ratio, excitation)

        friction = drawn("coulomb_viscous_friction", case_seed)
        out.append((friction, drawn("constant_load", case_seed + 7)))
    return out


def main(argv=None) -> int:
    from .plants import PLANTS
    from .run import run_case
    ap = argparse.ArgumentParser(prog="python -m diagnosis.benchmark.ball_screw", description=__doc__.split("\n\n")[1])
    ap.add_argument("--cases", type=int, default=10)
    ap.add_argument("--seed", type=int, default=11)
    ap.add_argument("--dir", default=None, help="where the recordings go (default: a temporary directory)")
    a = ap.parse_args(argv)
    work = Path(a.dir) if a.dir else Path(tempfile.mkdtemp(prefix="ball-screw-"))
    work.mkdir(parents=True, exist_ok=True)
    first = second = both = 0
    for friction, load in cases(a.cases, a.seed):
        r = run_case(friction, PLANTS, work, second=load)
        found = (bool(r.get("first_found")), bool(r.get("also_found")))
        first, second, both = first + found[0], second + found[1], both + all(found)
        print(f"{r['label']}: {', '.join(r.get('answers') or ['none'])}; friction {'found' if found[0] else 'missed'}, "
              f"load {'found' if found[1] else 'missed'}; held-out improvement {r.get('improvement', float('nan')):.2f}; "
              f"{r.get('seconds_diagnose', float('nan')):.0f} s{' ' + r['error'] if r.get('error') else ''}", flush=True)
    print(f"friction named {first}/{a.cases}, load {second}/{a.cases}, both {both}/{a.cases}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
