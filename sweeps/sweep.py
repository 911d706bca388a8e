"""``run_sweep``: a spec in, a directory of results and plots out (the library call behind
``bondcosim sweep`` and ``bondcosim montecarlo``)."""
from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

from .distributions import Grid, parse
from .engine import ExecutionStats, execute
from .errors import DistributionError, SpecError
from .runners import ScenarioRunner, make_runner, plan_runs
from .spec import ScenarioTarget, SweepSpec
from .store import RunStore
from .summary import metric_columns, quantile_table, sensitivity, varied_columns

__all__ = ["run_sweep", "SweepResult", "montecarlo_spec", "summarise"]


@dataclass(frozen=True)
class SweepResult:
    """A finished (or resumed) sweep.

    Attributes
    ----------
    directory : pathlib.Path
    table : pandas.DataFrame
        Every row of ``runs.parquet``: ``run_id``, ``status``, ``error``,
        ``seed``, ``duration_s`` (s), ``worker``, ``param.*`` (SI),
        ``metric.*`` (the metric's unit), ``output.*``.
    stats : ExecutionStats
        What this session ran (``n_run``, ``n_skipped``, timings).
    summary : dict
        ``summary.json``: counts, quantiles per metric, sensitivity ranking.
    files : dict str -> pathlib.Path
        ``runs``, ``summary`` and the plots.
    """

    directory: Path
    table: object
    stats: ExecutionStats
    summary: dict
    files: dict

    @property
    def n_failed(self) -> int:
        """Failed runs in the whole table."""
        return int((self.table["status"] != "ok").sum())

    def metric(self, name: str):
        """Values of metric `name` (without ``metric.``) by run id, NaN for failed runs (pandas Series)."""
        return self.table.set_index("run_id")[f"metric.{name}"]


def montecarlo_spec(scenario: str, *, samples: int, vary, fixed=None, seed: int = 0, quick: bool = False,
                    metrics=()) -> SweepSpec:
    """The spec of ``bondcosim montecarlo``: `samples` draws of the laws in `vary` on one scenario.

    Parameters
    ----------
    scenario : str
    samples : int
    vary : mapping str -> str or iterable of "NAME=LAW"
        e.g. ``{"A1": "normal(1, 0.1)*nominal"}`` or ``["A1=normal(1,0.1)*nominal"]``.
    fixed : mapping str -> float, optional
    seed : int
    quick : bool
    metrics : sequence of str

    Raises
    ------
    DistributionError
        A law that does not parse, or a grid (a Monte-Carlo draws).
    SpecError
        ``NAME=LAW`` text without ``=``, or a number of samples that is not a whole number >= 1.
    """
    if isinstance(samples, bool) or not isinstance(samples, int) or samples < 1:
        raise SpecError("--samples", [f"the number of runs must be a whole number >= 1; found {samples!r}"])
    if not isinstance(vary, dict):
        pairs = {}
        for item in vary:
            name, sep, law = str(item).partition("=")
            if not sep or not name.strip() or not law.strip():
                raise SpecError("--vary", [f"{item!r} is not NAME=LAW, e.g. A1=normal(1,0.1)*nominal"])
            pairs[name.strip()] = law.strip()
        vary = pairs
    laws = {}
    for name, text in vary.items():
        law = parse(name, text)
        if isinstance(law, Grid):
            raise DistributionError(name, text, "a Monte-Carlo draws: give a random law (a grid belongs in a "
                                                "sweep spec)")
        laws[name] = law
    return SweepSpec(ScenarioTarget(scenario, quick), laws, dict(fixed or {}), int(samples), int(seed),
                     tuple(metrics), f"montecarlo-{scenario}")


def summarise(table, spec: SweepSpec, runner) -> dict:
    """Counts, quantiles of the plotted metrics, and the sensitivity ranking (``summary.json``)."""
    wanted = tuple(spec.metrics)
    if not wanted and isinstance(runner, ScenarioRunner):
        import reproductions as scenarios
        wanted = tuple(m for m in scenarios.headline_metrics(spec.target.name) if f"metric.{m}" in table)
    metrics = metric_columns(table, wanted)[:8]
    params = varied_columns(table)
    return {"name": spec.name, "n_runs": int(len(table)), "n_ok": int((table["status"] == "ok").sum()),
            "n_failed": int((table["status"] != "ok").sum()),
            "errors": {str(k): int(v) for k, v in
                       table.loc[table["status"] != "ok", "error"].str.split(":").str[0].value_counts().items()},
            "metrics": [m.removeprefix("metric.") for m in metrics],
            "varied": [p.removeprefix("param.") for p in params],
            "units": {p.removeprefix("param."): runner.units.get(p.removeprefix("param."), "") for p in params},
            "quantiles": quantile_table(table, metrics), "sensitivity": sensitivity(table, metrics, params)}


def run_sweep(spec: SweepSpec, out, *, resume: bool = False, workers=None, scheduler=None, client=None,
              chunk_size=None, graph=None, plots: bool = True, progress=True, on_chunk=None,
              flush_interval_s: float = 0.0) -> SweepResult:
    """Run every run of `spec` not yet in `out`, streaming rows to Parquet; then summarise and plot.

    Parameters
    ----------
    spec : SweepSpec
    out : path-like
        The results directory (:mod:`sweeps.store`); created if needed.
    resume : bool
        Continue the sweep in `out` (same spec): run only the missing run ids.
    workers : int, optional
        Local Dask cluster of this many processes (default: one per core); 0: serial.
    scheduler : str, optional
        A running Dask scheduler's address instead (``tcp://HOST:PORT``).
    client : distributed.Client, optional
        An existing client instead.
    chunk_size : int, optional
        Runs per task (default: :mod:`sweeps.engine`).
    graph : BondGraph, optional
        A model target already loaded.
    plots : bool
        Write the plots (:mod:`sweeps.plots`).
    progress : file or bool
        Where the progress bar goes (``True``: stderr; ``None``/``False``: nowhere).
    on_chunk : callable, optional
        Called with each finished chunk's rows.
    flush_interval_s : float, s
        Write rows at most once per interval instead of once per chunk (:func:`sweeps.engine.execute`).

    Returns
    -------
    SweepResult

    Raises
    ------
    SpecError, UnknownNameError, GraphError
        Bad names in the spec (before anything runs).
    StoreError
        `out` holds another sweep, or results without `resume`.
    MetricError, EngineError
        See :func:`sweeps.engine.execute`.
    """
    runner = make_runner(spec, graph=graph)
    runs = plan_runs(spec, runner.nominal)
    store = RunStore(out, spec.to_dict(), len(runs), resume=resume)
    if len(store.done()) < len(runs):
        # the C libraries are recorded for workers only: a serial sweep runs in this process
        runner.prepare(ship_kernels=not (workers == 0 and scheduler is None and client is None))
    stats = execute(runner, runs, store, workers=workers, scheduler=scheduler, client=client,
                    chunk_size=chunk_size, progress=progress, on_chunk=on_chunk,
                    flush_interval_s=flush_interval_s)
    files = {"runs": store.consolidate()}
    table = store.read()
    summary = summarise(table, spec, runner)
    summary["session"] = {k: getattr(stats, k) for k in stats.__dataclass_fields__}
    files["summary"] = Path(out) / "summary.json"
    files["summary"].write_text(json.dumps(summary, indent=1, default=float))
    if plots:
        from .plots import save_plots
        files.update(save_plots(table, out, metrics=[f"metric.{m}" for m in summary["metrics"]],
                                params=[f"param.{p}" for p in summary["varied"]],
                                grid_params=[f"param.{n}" for n in spec.grid_names if f"param.{n}" in table],
                                ranking=summary["sensitivity"], units=summary["units"]))
    return SweepResult(Path(out), table, stats, summary, files)
