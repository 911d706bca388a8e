"""The sweep subcommands of the console script: ``sweep``, ``montecarlo``, ``diagnose-batch``.

Each is one library call of :mod:`sweeps`; imports happen inside the handlers.
"""
from __future__ import annotations

import sys

__all__ = ["add_parsers", "COMMANDS"]


def _engine_options(p) -> None:
    p.add_argument("--out", required=True, metavar="DIR", help="results directory (runs.parquet, plots)")
    p.add_argument("--resume", action="store_true", help="continue the sweep in DIR: run only the missing runs")
    p.add_argument("--scheduler", default=None, metavar="ADDR",
                   help="run on a running Dask scheduler, e.g. tcp://10.0.0.5:8786 (default: a local cluster)")
    p.add_argument("--workers", type=int, default=None, metavar="K",
                   help="local cluster of K worker processes (default: one per core); 0: serial in this process")


def add_parsers(sub) -> None:
    """Add the three subcommands to the argparse `sub` parsers."""
    p = sub.add_parser("sweep", help="run a sweep spec (TOML/YAML): a scenario or model over grids or "
                       "distributions, one Parquet row per run, plots")
    p.add_argument("spec", help="spec file (.toml, .yaml); keys in docs/sweeps.md")
    _engine_options(p)
    p.add_argument("--chunk-size", type=int, default=None, metavar="N", help="runs per Dask task (default: auto)")
    p.add_argument("--flush-interval", type=float, default=0.0, metavar="S",
                   help="write results at most every S s instead of per chunk (large clusters; default 0)")

    p = sub.add_parser("montecarlo", help="Monte-Carlo of a scenario: draw its parameters, run it N times")
    p.add_argument("scenario", help="scenario name (bondcosim cosim --list)")
    p.add_argument("--samples", type=int, required=True, metavar="N", help="number of runs")
    p.add_argument("--vary", action="append", default=[], required=True, metavar="NAME=LAW",
                   help="e.g. A1=normal(1,0.1)*nominal, c_s=uniform(0.8,1.2)*nominal (repeatable)")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="parameter value for every run, SI (repeatable), e.g. segment_s=1")
    p.add_argument("--seed", type=int, default=0, help="seed of the draws (default 0)")
    p.add_argument("--quick", action="store_true", help="the scenario's shortened run")
    p.add_argument("--metric", action="append", default=[], metavar="NAME",
                   help="keep only these metrics, e.g. ukf.angle.I (repeatable; default all)")
    _engine_options(p)

    p = sub.add_parser("diagnose-batch", help="diagnose many recordings against one model; fleet summary")
    p.add_argument("model", help="built-in name, graph .json file, or .py file with build()")
    p.add_argument("recordings", help="glob pattern of CSV files, quoted: 'recordings/*.csv'")
    p.add_argument("--input", action="append", default=[], metavar="NAME=COLUMN[:UNIT]", help="as for diagnose")
    p.add_argument("--output", action="append", default=[], required=True, metavar="NAME=COLUMN[:UNIT]",
                   help="as for diagnose")
    p.add_argument("--time", default=None, metavar="COLUMN[:UNIT]", help="as for diagnose")
    p.add_argument("--holdout", type=float, default=0.3, help="as for diagnose (default 0.3)")
    p.add_argument("--top", type=int, default=3, help="as for diagnose (default 3)")
    p.add_argument("--max-effects", type=int, default=2, metavar="N", help="as for diagnose (default 2)")
    _engine_options(p)


def _values(items) -> dict:
    """``--set NAME=VALUE`` pairs as numbers (SI)."""
    from bondgraph.errors import ParameterError
    values = {}
    for item in items:
        name, sep, text = item.partition("=")
        try:
            if not sep or not name.strip():
                raise ValueError
            values[name.strip()] = float(text)
        except ValueError:
            raise ParameterError(f"--set {item!r} is not NAME=NUMBER", name=name.strip()) from None
    return values


def _print_sweep(result) -> None:
    s = result.summary
    print(f"{s['name']}: {s['n_runs']} runs, {s['n_ok']} ok, {s['n_failed']} failed "
          f"({result.stats.n_run} run now, {result.stats.n_skipped} resumed; engine {result.stats.engine}, "
          f"{result.stats.wall_s:.1f} s)")
    for error, count in s["errors"].items():
        print(f"  failed: {count} x {error}")
    if s["quantiles"]:
        print(f"  {'metric':<28} {'median':>10} {'5 %':>10} {'95 %':>10}")
    for m, q in s["quantiles"].items():
        print(f"  {m:<28} {q['q50']:>10.4g} {q['q05']:>10.4g} {q['q95']:>10.4g}")
    ranked = [r for r in s["sensitivity"] if r["spearman"] == r["spearman"]]
    for m in s["metrics"]:
        top = [r for r in ranked if r["metric"] == m][:3]
        if top:
            print(f"  {m} most sensitive to: " + ", ".join(f"{r['param']} ({r['spearman']:+.2f})" for r in top))
    for key, path in result.files.items():
        print(f"  wrote {path}")


def _cmd_sweep(args) -> int:
    from sweeps import ModelTarget, load_spec, run_sweep
    spec = load_spec(args.spec)
    graph = None
    if isinstance(spec.target, ModelTarget) and spec.target.model.endswith(".py"):   # the CLI's own loader
        from plants import load as load_model
        graph = load_model(spec.target.model)
    result = run_sweep(spec, args.out, resume=args.resume, workers=args.workers, scheduler=args.scheduler,
                       chunk_size=args.chunk_size, graph=graph, flush_interval_s=args.flush_interval)
    _print_sweep(result)
    return 0


def _cmd_montecarlo(args) -> int:
    from sweeps import montecarlo_spec, run_sweep
    spec = montecarlo_spec(args.scenario, samples=args.samples, vary=args.vary, fixed=_values(args.set),
                           seed=args.seed, quick=args.quick, metrics=args.metric)
    result = run_sweep(spec, args.out, resume=args.resume, workers=args.workers, scheduler=args.scheduler)
    _print_sweep(result)
    return 0


def _cmd_diagnose_batch(args) -> int:
    from sweeps import diagnose_batch
    from sweeps.fleet import summary_text
    from plants import load as load_model
    result = diagnose_batch(load_model(args.model), args.recordings, args.out, inputs=args.input,
                            outputs=args.output, time=args.time, holdout=args.holdout, top=args.top,
                            max_effects=args.max_effects, resume=args.resume, workers=args.workers,
                            scheduler=args.scheduler)
    print(summary_text(result.summary))
    for path in result.files.values():
        print(f"  wrote {path}", file=sys.stdout)
    return 0


COMMANDS = {"sweep": _cmd_sweep, "montecarlo": _cmd_montecarlo, "diagnose-batch": _cmd_diagnose_batch}
