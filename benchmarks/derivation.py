"""Derivation time: bondgraph vs BondGraphTools on a mass-spring-damper chain.

The graph is a chain of ``N`` stages driven by one effort source ``F``::

    Se:F -> 1:j1_1 -> 0:j0_1 -> 1:j1_2 -> 0:j0_2 -> ... -> 0:j0_N
              |  \\        |
            I:m1 R:b1   C:k1        (I:mk, R:bk on 1:j1_k; C:kk on 0:j0_k)

with ``m_k = 1``, ``b_k = 0.5``, ``k_k = 0.01`` (compliance), so ``2 N``
states.  Every bond points away from the source (power direction).

What is timed is CPU time (``time.process_time``) of building the graph plus
deriving its state equations:

* ours -- ``build_chain(n)`` then ``g.equations()``, in this process, best of
  ``--repeats`` runs (imports and a small warm-up run are outside the timing);
* BondGraphTools 0.4.6 -- building the same graph with ``bgt.new`` /
  ``bgt.add`` / ``bgt.connect`` then reading ``model.constitutive_relations``,
  one run per size, each in its own process started with the Python of a
  separate virtual environment (BondGraphTools needs sympy 1.12.x)::

      python -m venv /work/bgt-venv
      /work/bgt-venv/bin/pip install bondgraphtools==0.4.6 sympy==1.12.1

  Its import (about a second) is outside the timing.  The process is given a
  CPU-time limit of ``--bgt-timeout`` seconds (default 300); once a size
  exceeds it, the larger sizes are not attempted and are printed as
  ``> timeout``.

Run from the repository root::

    python benchmarks/derivation.py
    python benchmarks/derivation.py --sizes 5 10 20 --bgt-python /work/bgt-venv/bin/python
    python benchmarks/derivation.py --skip-bgt --sizes 5 10 20 50 100 200

Targets (project issue): at least 100x faster than BondGraphTools at N = 20,
and N = 200 derived in under 10 s.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time

SIZES = (5, 10, 20, 50, 100, 200)
DEFAULT_BGT_PYTHON = "/work/bgt-venv/bin/python"
DEFAULT_BGT_TIMEOUT = 300.0
TARGET_RATIO_N = 20
TARGET_RATIO = 100.0
TARGET_BIG_N = 200
TARGET_BIG_SECONDS = 10.0

MASS, DAMPING, COMPLIANCE = 1.0, 0.5, 0.01

_RESULT_TAG = "BGT_RESULT "


# --------------------------------------------------------------------------
# ours
# --------------------------------------------------------------------------
def build_chain(n: int):
    """The N-stage chain built with bondgraph's API (not yet derived)."""
    from plants.library import mass_spring_chain

    return mass_spring_chain(n, m=MASS, b=DAMPING, compliance=COMPLIANCE)


def time_ours(n: int, repeats: int = 3) -> dict:
    """Best-of-``repeats`` CPU seconds of build, and of build + equations()."""
    best_build = best_total = float("inf")
    nstates = None
    for _ in range(max(1, repeats)):
        t0 = time.process_time()
        g = build_chain(n)
        t1 = time.process_time()
        eqs = g.equations()
        t2 = time.process_time()
        best_build = min(best_build, t1 - t0)
        best_total = min(best_total, t2 - t0)
        nstates = len(eqs.f)
    return {"build": best_build, "total": best_total, "states": nstates}


# --------------------------------------------------------------------------
# BondGraphTools (runs in the bgt virtualenv: --bgt-worker N)
# --------------------------------------------------------------------------
def bgt_worker(n: int, cpu_limit: float | None = None) -> None:
    """Build and derive the chain with BondGraphTools; print one JSON line.

    ``cpu_limit``: CPU seconds allowed for build + derivation (the import
    is not counted); the process is killed by SIGXCPU beyond it (POSIX).
    """
    import contextlib
    import io

    t0 = time.process_time()
    # BondGraphTools prints a warning on stdout when scikit.odes (its optional
    # simulator) is missing; keep stdout for the result line.
    with contextlib.redirect_stdout(io.StringIO()):
        import BondGraphTools as bgt
    t_import = time.process_time() - t0
    if cpu_limit is not None:
        _set_cpu_limit(time.process_time() + cpu_limit)

    t0 = time.process_time()
    model = bgt.new(name="chain")
    source = bgt.new("Se", name="F")  # no value: its effort is a control variable
    bgt.add(model, source)
    prev = source
    for k in range(1, n + 1):
        j1 = bgt.new("1", name=f"j1_{k}")
        mass = bgt.new("I", name=f"m{k}", value=MASS)
        damper = bgt.new("R", name=f"b{k}", value=DAMPING)
        j0 = bgt.new("0", name=f"j0_{k}")
        spring = bgt.new("C", name=f"k{k}", value=COMPLIANCE)
        bgt.add(model, j1, mass, damper, j0, spring)
        bgt.connect(prev, j1)
        bgt.connect(j1, mass)
        bgt.connect(j1, damper)
        bgt.connect(j1, j0)
        bgt.connect(j0, spring)
        prev = j0
    t1 = time.process_time()
    relations = model.constitutive_relations
    t2 = time.process_time()
    print(_RESULT_TAG + json.dumps({
        "n": n, "import": t_import, "build": t1 - t0, "total": t2 - t0,
        "states": len(model.state_vars), "relations": len(relations),
    }), flush=True)


def _set_cpu_limit(total_seconds: float) -> None:
    """Limit this process's total CPU time (no-op where unsupported)."""
    try:
        import resource
    except ImportError:
        return
    soft = max(1, int(total_seconds + 0.999))
    resource.setrlimit(resource.RLIMIT_CPU, (soft, soft + 5))


def time_bgt(n: int, python: str, timeout: float) -> dict | None:
    """Run :func:`bgt_worker` in ``python``; None when it exceeds ``timeout``.

    ``timeout`` is CPU seconds of build + derivation (RLIMIT_CPU set by the
    worker after its import); a wall-clock limit of twice that plus a minute
    is a backstop.
    """
    cmd = [python, os.path.abspath(__file__), "--bgt-worker", str(n),
           "--bgt-timeout", repr(float(timeout))]
    try:
        proc = subprocess.run(
            cmd, capture_output=True, text=True, timeout=2 * timeout + 60)
    except subprocess.TimeoutExpired:
        return None
    for line in proc.stdout.splitlines():
        if line.startswith(_RESULT_TAG):
            return json.loads(line[len(_RESULT_TAG):])
    if proc.returncode < 0:  # killed: SIGXCPU at the CPU limit (or SIGKILL)
        return None
    raise RuntimeError(
        f"BondGraphTools worker failed for N={n} (exit {proc.returncode}):\n"
        f"{proc.stderr.strip()[-2000:]}"
    )


def _bgt_available(python: str) -> bool:
    if not os.path.exists(python):
        return False
    probe = subprocess.run(
        [python, "-c", "import BondGraphTools"], capture_output=True, text=True)
    return probe.returncode == 0


_BGT_SETUP = """\
BondGraphTools is not available at {python}.  Create its environment with
    python -m venv /work/bgt-venv
    /work/bgt-venv/bin/pip install bondgraphtools==0.4.6 sympy==1.12.1
and pass --bgt-python /work/bgt-venv/bin/python (the default), or use --skip-bgt."""


# --------------------------------------------------------------------------
# driver
# --------------------------------------------------------------------------
def _fmt(seconds: float | None) -> str:
    if seconds is None:
        return "-"
    if seconds < 1:
        return f"{seconds:.4f}"
    return f"{seconds:.3f}" if seconds < 10 else f"{seconds:.1f}"


def main(sizes=SIZES, bgt_python: str = DEFAULT_BGT_PYTHON,
         bgt_timeout: float = DEFAULT_BGT_TIMEOUT, skip_bgt: bool = False,
         repeats: int = 3) -> list[dict]:
    sizes = sorted(int(n) for n in sizes)
    run_bgt = not skip_bgt
    if run_bgt and not _bgt_available(bgt_python):
        print(_BGT_SETUP.format(python=bgt_python), file=sys.stderr)
        run_bgt = False

    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    if root not in sys.path:  # run as `python benchmarks/derivation.py`
        sys.path.insert(0, root)
    time_ours(2, repeats=1)  # imports + warm-up, outside the timing

    header = (f"{'N':>5}  {'states':>6}  {'ours build (s)':>14}  {'ours (s)':>9}  "
              f"{'BGT (s)':>10}  {'BGT/ours':>9}")
    print("CPU seconds, graph build + derivation"
          + ("" if run_bgt else "  (BondGraphTools not run)"))
    print(header)
    print("-" * len(header))
    rows = []
    bgt_stopped = False
    for n in sizes:
        row = {"n": n, "ours": None, "ours_build": None, "bgt": None,
               "bgt_timeout": False, "bgt_skipped": False, "states": None}
        r = time_ours(n, repeats=repeats)
        row.update(ours=r["total"], ours_build=r["build"], states=r["states"])
        bgt_txt = "-"
        if run_bgt and bgt_stopped:
            row["bgt_skipped"] = True
            bgt_txt = "> timeout"
        elif run_bgt:
            b = time_bgt(n, bgt_python, bgt_timeout)
            if b is None:
                row["bgt_timeout"] = bgt_stopped = True
                bgt_txt = "> timeout"
            else:
                row["bgt"] = b["total"]
                bgt_txt = _fmt(b["total"])
                if row["states"] is not None and row["states"] != b["states"]:
                    print(f"warning: N={n}: ours has {row['states']} states,"
                          f" BondGraphTools {b['states']}", file=sys.stderr)
                row["states"] = row["states"] or b["states"]
        if row["ours"] and row["bgt"]:
            ratio = f"{row['bgt'] / row['ours']:.0f}x"
        elif row["ours"] and row["bgt_timeout"]:
            ratio = f">{bgt_timeout / row['ours']:.0f}x"
        else:
            ratio = "-"
        states = "-" if row["states"] is None else str(row["states"])
        print(f"{n:>5}  {states:>6}  {_fmt(row['ours_build']):>14}  "
              f"{_fmt(row['ours']):>9}  {bgt_txt:>10}  {ratio:>9}", flush=True)
        rows.append(row)
    if run_bgt and bgt_stopped:
        print(f"> timeout: over the {bgt_timeout:g} s CPU limit (--bgt-timeout),"
              " or not attempted after a smaller N was")

    # targets
    by_n = {r["n"]: r for r in rows}
    r20, r200 = by_n.get(TARGET_RATIO_N), by_n.get(TARGET_BIG_N)
    if r20 and r20["ours"] and r20["bgt"]:
        ratio = r20["bgt"] / r20["ours"]
        print(f"target N={TARGET_RATIO_N}: >= {TARGET_RATIO:g}x faster than "
              f"BondGraphTools -> {ratio:.0f}x {'OK' if ratio >= TARGET_RATIO else 'MISSED'}")
    if r200 and r200["ours"]:
        ok = r200["ours"] < TARGET_BIG_SECONDS
        print(f"target N={TARGET_BIG_N}: under {TARGET_BIG_SECONDS:g} s -> "
              f"{r200['ours']:.2f} s {'OK' if ok else 'MISSED'}")
    return rows


def _parse(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--sizes", type=int, nargs="+", default=list(SIZES),
                   help="chain lengths N (default: %(default)s)")
    p.add_argument("--bgt-python", default=DEFAULT_BGT_PYTHON,
                   help="Python of the BondGraphTools venv (default: %(default)s)")
    p.add_argument("--bgt-timeout", type=float, default=DEFAULT_BGT_TIMEOUT,
                   help="CPU seconds allowed per BondGraphTools size (default: %(default)s)")
    p.add_argument("--skip-bgt", action="store_true",
                   help="time only our derivation")
    p.add_argument("--repeats", type=int, default=3,
                   help="runs of ours per size, best kept (default: %(default)s)")
    p.add_argument("--bgt-worker", type=int, metavar="N", help=argparse.SUPPRESS)
    return p.parse_args(argv)


if __name__ == "__main__":
    args = _parse()
    if args.bgt_worker is not None:
        bgt_worker(args.bgt_worker, cpu_limit=args.bgt_timeout)
    else:
        main(sizes=args.sizes, bgt_python=args.bgt_python,
             bgt_timeout=args.bgt_timeout, skip_bgt=args.skip_bgt,
             repeats=args.repeats)
