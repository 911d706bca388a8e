"""Generated C from the causal assignments vs from the flat (substituted) equations.

For each model, the same process generates and compiles the ``main`` library
(f, h, held_update, Newton, RK4) twice: once from the model's ordered causal
assignments (what bondcosim does) and once from a copy of the equations
without them (every right-hand side fully substituted, sympy's cse alone),
and prints generation time, compile time and source size with their ratios.

    python benchmarks/codegen.py            # pam and a 200-stage chain
    python benchmarks/codegen.py --quick    # pam_locked and a 5-stage chain
"""
from __future__ import annotations

import argparse
import dataclasses
import time

from plants import library
from bondgraph.numerics.c_build import compile_source, find_compiler
from bondgraph.numerics.codegen_c import generate_source
from plants.library.chain import mass_spring_chain


def _flat(eqs):
    """The same equations without the assignments (the flat form only)."""
    return dataclasses.replace(eqs, assignments=(), f_short=(), h_short=(), held_update_short=())


def _measure(eqs, compiler, nonce: str) -> tuple[float, float, int]:
    t0 = time.perf_counter()
    source = generate_source(eqs, part="main")
    t1 = time.perf_counter()
    compile_source(source + f"\n/* {nonce} */\n", compiler=compiler)   # a nonce defeats the build cache
    t2 = time.perf_counter()
    return t1 - t0, t2 - t1, len(source)


def main(models=None) -> list[dict]:
    """Print and return one row per model: gen/compile seconds and source chars, both ways."""
    compiler = find_compiler()
    models = models or {"pam": library.build("pam"), "chain200": mass_spring_chain(200)}
    rows = []
    print(f"{'model':<10} {'form':<12} {'generate s':>10} {'compile s':>10} {'source':>8}")
    for name, graph in models.items():
        eqs = graph.equations()
        nonce = f"{time.time_ns()}"
        flat = _measure(_flat(eqs), compiler, "flat" + nonce)
        assigned = _measure(eqs, compiler, "assigned" + nonce)
        for form, (gen, comp, size) in (("flat + cse", flat), ("assignments", assigned)):
            print(f"{name:<10} {form:<12} {gen:>10.3f} {comp:>10.3f} {size:>8}")
        print(f"{name:<10} {'ratio':<12} {assigned[0] / flat[0]:>10.2f} {assigned[1] / flat[1]:>10.2f} "
              f"{assigned[2] / flat[2]:>8.2f}")
        rows.append({"model": name, "flat": flat, "assignments": assigned})
    return rows


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    main({"pam_locked": library.build("pam-locked"), "chain5": mass_spring_chain(5)} if args.quick else None)
