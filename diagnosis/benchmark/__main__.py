"""``python -m diagnosis.benchmark [--cases N] [--seed S] [--report DIR] [--jobs J] [--plants A,B] [--compound]
[--detune F] [--sampling F] [--kinds A,B]``.

Draws N cases (default 80), diagnoses each recording as a user would, and
writes into DIR (default ``benchmark-report``): one JSON file per case
(``cases/LABEL.json``; a rerun with the same DIR skips finished cases),
``results.json`` (all scores and the summary), ``results.md`` (the tables)
and ``results.png`` (confusion matrix, held-out improvement, time per case).
With ``--compound`` every effect case conceals a second effect too
(:mod:`diagnosis.benchmark.compound`); with ``--detune F`` each nominal has one storage
element's value off by up to the fraction F (:mod:`diagnosis.benchmark.detune`); with ``--sampling F``
each recording's rate and length are scaled by up to F (:mod:`diagnosis.benchmark.sampling`).  Each variant
needs a report directory of its own (a case's file is named by its draw).
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

import numpy as np

from ..errors import BenchmarkError
from .compound import compound_label, second_effect
from .draw import KIND_LISTS, KINDS, draw_cases
from .plants import PLANT_LISTS, PLANTS
from .report import summarise, write_report
from .run import run_case


def _work(job):
    """One case in a worker process: ``(spec, workdir, second, options)``, `options` the keyword
    arguments of :func:`~diagnosis.benchmark.run.run_case` that every case shares."""
    spec, workdir, second, options = job
    import os
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    return run_case(spec, PLANTS, workdir, second=second, **options)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m diagnosis.benchmark", description=__doc__.split("\n\n")[0])
    ap.add_argument("--cases", type=int, default=80, help="number of cases (default 80)")
    ap.add_argument("--seed", type=int, default=2026, help="benchmark seed (default 2026)")
    ap.add_argument("--report", default="benchmark-report", help="output directory")
    ap.add_argument("--jobs", type=int, default=1, help="cases diagnosed in parallel (processes)")
    ap.add_argument("--plants", default="",
                    help="comma-separated plant names, or 'fast' (diagnosis.benchmark.plants.FAST), 'before-34' or "
                         "'fast-before-34' (those drawn until session 33: a seed's cases as then drawn; default: all)")
    ap.add_argument("--only", default="", help="comma-separated case indices to run")
    ap.add_argument("--kinds", default="",
                    help="comma-separated effect kinds to draw, or 'before-32' / 'before-34' / 'before-35' / "
                         "'before-36' (the kinds drawn until session 31 / 33 / 34 / 35: a seed's cases as then drawn; "
                         "default: every kind)")
    ap.add_argument("--max-effects", type=int, default=2, help="passed to diagnose (default 2)")
    ap.add_argument("--compound", action="store_true",
                    help="a second concealed effect in every effect case (diagnosis.benchmark.compound)")
    ap.add_argument("--detune", type=float, default=0.0,
                    help="each nominal's one storage value off by up to this fraction (diagnosis.benchmark.detune)")
    ap.add_argument("--detune-elements", default="IC", choices=("IC", "ICR"),
                    help="the elements --detune may pick: storages (IC, default) or resistances too (ICR)")
    ap.add_argument("--sampling", type=float, default=1.0,
                    help="each recording's rate scaled by up to this factor either way, its duration by its "
                         "square root (diagnosis.benchmark.sampling; default 1: as the plant records)")
    a = ap.parse_args(argv)
    if a.cases < 1 or a.jobs < 1:
        ap.error("--cases and --jobs must be positive")
    if not 0.0 <= a.detune < 1.0:
        ap.error(f"--detune must be a fraction in [0, 1), got {a.detune}")
    if not a.sampling >= 1.0:
        ap.error(f"--sampling must be a factor of at least 1, got {a.sampling}")
    plants = PLANTS
    if a.plants in PLANT_LISTS:
        plants = PLANT_LISTS[a.plants]
    elif a.plants:
        unknown = [p for p in a.plants.split(",") if p not in PLANTS]
        if unknown:
            ap.error(f"unknown plant(s) {', '.join(unknown)}; known: {', '.join(PLANTS)}")
        plants = {p: PLANTS[p] for p in a.plants.split(",")}
    kinds = KIND_LISTS.get(a.kinds) or (tuple(a.kinds.split(",")) if a.kinds else KINDS)
    try:
        specs = draw_cases(a.cases, a.seed, plants, kinds)
    except BenchmarkError as exc:          # an unknown kind: draw_cases names it
        ap.error(str(exc))
    if a.only:
        keep = {int(i) for i in a.only.split(",")}
        specs = [s for s in specs if s.index in keep]
    out = Path(a.report)
    (out / "cases").mkdir(parents=True, exist_ok=True)
    (out / "recordings").mkdir(exist_ok=True)
    seconds = {s.index: second_effect(s, plants[s.plant](), kinds) if a.compound else None for s in specs}
    results, todo = [], []
    for s in specs:
        f = out / "cases" / f"{compound_label(s, seconds[s.index])}.json"
        if f.exists():
            results.append(json.loads(f.read_text()))
        else:
            todo.append(s)
    print(f"benchmark: {len(specs)} cases ({len(results)} done before), seed {a.seed}, {a.jobs} job(s)",
          file=sys.stderr, flush=True)
    start = time.perf_counter()
    options = dict(max_effects=a.max_effects, detune=a.detune, detune_kinds=a.detune_elements, sampling=a.sampling)
    jobs = [(s, out / "recordings", seconds[s.index], options) for s in todo]
    done = 0

    def record(r):
        nonlocal done
        done += 1
        results.append(r)
        (out / "cases" / f"{r['label']}.json").write_text(json.dumps(r, indent=1))
        el = time.perf_counter() - start
        eta = el / done * (len(todo) - done)
        verdict = ("GEN-ERROR " + r["generator_error"]) if "generator_error" in r else (
            f"{'ok ' if r['kind_ok'] else 'BAD'} {r['kind']} -> {r['answer_kind']}"
            f" ({'place ok' if r['place_ok'] else 'place ' + (r['answer_place'] or '-')})"
            f" {r['seconds_diagnose']:.0f} s")
        if r.get("also_kind"):
            verdict += (f"; found: first {r['first_found']}, second {r['also_found']} ({', '.join(r['answers'])}); "
                        f"effect-to-noise with both: {r.get('first_visible', np.nan):.3g} / "
                        f"{r.get('also_visible', np.nan):.3g}")
        if r.get("detuned"):
            d = r["detuned"]
            verdict += (f"; nominal {d['parameter']} x {d['factor']:.3f} "
                        f"{'named' if r['detuned_named'] else 'not named'} ({', '.join(r['answers']) or 'none'})")
        print(f"benchmark: [{done}/{len(todo)} {el:6.0f} s, eta {eta:5.0f} s] {r['label']}: {verdict}",
              file=sys.stderr, flush=True)

    if a.jobs == 1:
        for j in jobs:
            record(_work(j))
    else:
        with ProcessPoolExecutor(a.jobs) as pool:
            for fut in as_completed([pool.submit(_work, j) for j in jobs]):
                record(fut.result())
    summary = summarise(results)
    write_report(results, summary, out, seed=a.seed)
    print(json.dumps(summary["headline"], indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
