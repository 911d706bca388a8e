"""Fleet diagnosis: one :func:`diagnosis.diagnose.diagnose` per recording, on the sweep engine,
and a fleet summary -- which physics was found how often, where, with what parameters, and how
much it improved the held-out fit.

Each recording is a run (``param.recording``: its path); its row holds the
kinds found (``metric.kinds``, ``;``-separated, ``none`` when nothing is
missing), where they attach (``metric.places``), their fitted parameters
(``metric.parameters``, JSON: a list of one dict per effect, in that order), the
held-out NRMSE before and after (``metric.nominal_nrmse.OUTPUT``,
``metric.improved_nrmse.OUTPUT``), the improvement ``1 - improved / nominal``
(``metric.improvement.OUTPUT``) and the whole report (``metric.report``, JSON
of :meth:`DiagnosisReport.to_json`).  Workers read the recordings by path: on a cluster the paths must be on storage
every worker sees.
"""
from __future__ import annotations

import glob as _glob
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .engine import ExecutionStats, execute
from .errors import SweepError
from .runners import RunSpec
from .store import RunStore

__all__ = ["diagnose_batch", "FleetResult", "DiagnosisRunner", "fleet_summary"]


class DiagnosisRunner:
    """Diagnoses one recording per call; the model travels as its JSON description.

    Parameters
    ----------
    graph : BondGraph
    options : dict
        Keyword arguments of :func:`diagnosis.diagnose.diagnose` (``inputs``,
        ``outputs``, ``time``, ``holdout``, ``uncertain``, ``top``, ``max_effects``).
    """

    #: Typical run time, s (a diagnosis takes seconds to minutes), for the chunk size.
    run_time_hint_s = 10.0

    def __init__(self, graph, options: dict):
        from bondgraph.io_json import graph_to_dict
        self.graph_data = graph_to_dict(graph)
        self.options = dict(options)
        self.nominal, self.units = {}, {}

    def prepare(self) -> None:
        """Nothing to build: the graph is shipped as JSON, the diagnosis derives what it needs."""

    def __call__(self, params: dict, seed: int) -> dict:
        from bondgraph.io_json import graph_from_dict
        from diagnosis.diagnose import diagnose
        report = diagnose(graph_from_dict(self.graph_data), params["recording"], **self.options)
        data = report.to_json()
        found = [m for m in data["missing_physics"] if m["kind"] != "none"]
        out = {"n_effects": float(len(found)), "kinds": ";".join(m["kind"] for m in found) or "none",
               "places": ";".join(m["attached_to"] for m in found),
               # one entry per effect, in the order of kinds and places: the same kind may be found twice
               "parameters": json.dumps([m["parameters"] for m in found]),
               "junction": data["location"]["junction"], "report": json.dumps(data)}
        for o, v in data["fit"]["nominal"].items():
            out[f"nominal_nrmse.{o}"] = float(v) if v is not None else float("nan")
        for o, v in data["fit"]["improved"].items():
            out[f"improved_nrmse.{o}"] = float(v) if v is not None else float("nan")
        out.update({f"improvement.{o}": float(v) for o, v in report.improvement().items()})
        return out


@dataclass(frozen=True)
class FleetResult:
    """A finished fleet diagnosis.

    Attributes
    ----------
    directory : pathlib.Path
    table : pandas.DataFrame
        One row per recording (see the module docstring).
    stats : ExecutionStats
    summary : dict
        :func:`fleet_summary`, also in ``fleet_summary.json``.
    files : dict str -> pathlib.Path
    """

    directory: Path
    table: object
    stats: ExecutionStats
    summary: dict
    files: dict


def _quantiles(v) -> dict:
    v = np.asarray(v, dtype=float)
    v = v[np.isfinite(v)]
    if not v.size:
        return {"n": 0}
    q05, q50, q95 = np.quantile(v, [0.05, 0.5, 0.95])
    return {"n": int(v.size), "median": float(q50), "q05": float(q05), "q95": float(q95)}


def _effects(row) -> list:
    """``(kind, place, fitted parameters)`` of each effect found in one ok row."""
    found = [k for k in row["metric.kinds"].split(";") if k != "none"]
    fitted = json.loads(row["metric.parameters"])
    if isinstance(fitted, dict):        # rows written before the list form: one entry per kind
        fitted = [fitted.get(k, {}) for k in found]
    return list(zip(found, row["metric.places"].split(";"), fitted))


def fleet_summary(table) -> dict:
    """Counts of each kind found (and of recordings with none), where each attached, the
    distribution of each kind's fitted parameters, and the held-out improvement
    (``1 - improved / nominal`` NRMSE) per output and per kind."""
    ok, bad = table[table["status"] == "ok"], table[table["status"] != "ok"]
    kinds, places, params, by_kind = {}, {}, {}, {}
    improvement_cols = [c for c in table.columns if c.startswith("metric.improvement.")]
    for _, row in ok.iterrows():
        effects = _effects(row)
        if not effects:
            kinds["none"] = kinds.get("none", 0) + 1
        for kind, place, fitted in effects:
            places.setdefault(kind, {})[place] = places.setdefault(kind, {}).get(place, 0) + 1
            for name, value in fitted.items():
                params.setdefault(kind, {}).setdefault(name, []).append(np.nan if value is None else value)
        for kind in dict.fromkeys(k for k, _, _ in effects):      # recordings, and their improvement, once per kind
            kinds[kind] = kinds.get(kind, 0) + 1
            by_kind.setdefault(kind, []).extend(row[c] for c in improvement_cols)
    return {"n_recordings": int(len(table)), "n_ok": int(len(ok)), "n_failed": int(len(table) - len(ok)),
            "failed": {str(r["param.recording"]): str(r["error"]) for _, r in bad.iterrows()},
            "kinds": dict(sorted(kinds.items(), key=lambda kv: -kv[1])), "places": places,
            "parameters": {k: {n: _quantiles(v) for n, v in p.items()} for k, p in params.items()},
            "improvement": {c.removeprefix("metric.improvement."): _quantiles(ok[c]) for c in improvement_cols},
            "improvement_by_kind": {k: _quantiles(v) for k, v in by_kind.items()}}


def summary_text(summary: dict) -> str:
    """The fleet summary in a few lines of plain text."""
    lines = [f"{summary['n_recordings']} recordings: {summary['n_ok']} diagnosed, {summary['n_failed']} failed"]
    for kind, count in summary["kinds"].items():
        where = ", ".join(f"{p} ({n})" for p, n in summary["places"].get(kind, {}).items())
        line = f"  {kind}: {count} recording(s)" + (f" at {where}" if where else "")
        imp = summary["improvement_by_kind"].get(kind, {})
        if imp.get("n"):
            line += f"; held-out NRMSE improved by {100 * imp['median']:.0f} % (median)"
        lines.append(line)
        for name, q in summary["parameters"].get(kind, {}).items():
            if q.get("n"):
                lines.append(f"      {name}: median {q['median']:.4g} (5-95 %: {q['q05']:.4g} .. {q['q95']:.4g})")
    for rec, error in summary["failed"].items():
        lines.append(f"  failed: {rec}: {error}")
    return "\n".join(lines)


def _plots(table, summary: dict, directory: Path) -> dict:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    written = {}
    if summary["kinds"]:
        fig, ax = plt.subplots(figsize=(6, 3))
        ax.bar(list(summary["kinds"]), list(summary["kinds"].values()))
        ax.set_ylabel("recordings")
        ax.set_title(f"missing physics found in {summary['n_ok']} recordings")
        ax.tick_params(axis="x", labelsize=8, rotation=20)
        fig.tight_layout()
        written["kinds"] = directory / "fleet_kinds.png"
        fig.savefig(written["kinds"], dpi=120)
        plt.close(fig)
    ok = table[table["status"] == "ok"]
    fitted = [(k, n) for k, p in summary["parameters"].items() for n in p]
    cols = [c for c in table.columns if c.startswith("metric.improvement.")]
    panels = len(fitted) + len(cols)
    if panels:
        fig, axes = plt.subplots(panels, 1, figsize=(6, 2.2 * panels + 0.4), squeeze=False)
        values = {}
        for _, row in ok.iterrows():
            for kind, _, p in _effects(row):
                for name, v in p.items():
                    values.setdefault((kind, name), []).append(np.nan if v is None else v)
        for ax, (kind, name) in zip(axes[:, 0], fitted):
            ax.hist(np.asarray(values.get((kind, name), []), dtype=float), bins=20)
            ax.set_title(f"{kind}: fitted {name}", fontsize=9)
        for ax, c in zip(axes[len(fitted):, 0], cols):
            ax.hist(100 * ok[c].to_numpy(dtype=float), bins=20, color="tab:green")
            ax.set_title(f"held-out NRMSE improvement, output {c.removeprefix('metric.improvement.')} (%)",
                         fontsize=9)
        fig.tight_layout()
        written["distributions"] = directory / "fleet_distributions.png"
        fig.savefig(written["distributions"], dpi=120)
        plt.close(fig)
    return written


def diagnose_batch(model, recordings, out, *, inputs, outputs, time=None, holdout: float = 0.3, uncertain=(),
                   top: int = 3, max_effects: int = 2, resume: bool = False, workers=None, scheduler=None,
                   client=None, plots: bool = True, progress=True) -> FleetResult:
    """Diagnose every recording against `model`; write one row each and the fleet summary into `out`.

    Parameters
    ----------
    model : BondGraph or str
        The nominal model (a built-in name or ``.json`` file is loaded).
    recordings : str or sequence of path-like
        A glob pattern (``"recordings/*.csv"``) or the files.
    out : path-like
        Results directory: ``runs.parquet``, ``fleet_summary.json``, ``fleet_summary.txt``, plots.
    inputs, outputs, time, holdout, uncertain, top, max_effects
        As :func:`diagnosis.diagnose.diagnose` (the same for every recording).
    resume, workers, scheduler, client, plots, progress
        As :func:`sweeps.run_sweep`.

    Returns
    -------
    FleetResult

    Raises
    ------
    SweepError
        The pattern matches no file.
    """
    if isinstance(model, str):
        from plants import load as load_model
        model = load_model(model)
    files = sorted(_glob.glob(recordings)) if isinstance(recordings, str) else [str(r) for r in recordings]
    if not files:
        raise SweepError(f"no recording matches {recordings!r}")
    files = [str(Path(f).resolve()) for f in files]
    options = {"inputs": list(inputs), "outputs": list(outputs), "time": time, "holdout": holdout,
               "uncertain": list(uncertain), "top": top, "max_effects": max_effects}
    runner = DiagnosisRunner(model, options)
    runs = [RunSpec(i, {"recording": f}, 0) for i, f in enumerate(files)]
    spec = {"kind": "diagnose-batch", "model": runner.graph_data.get("name", ""), "recordings": files, **options}
    store = RunStore(out, spec, len(runs), resume=resume)
    stats = execute(runner, runs, store, workers=workers, scheduler=scheduler, client=client, progress=progress)
    files_written = {"runs": store.consolidate()}
    table = store.read()
    summary = fleet_summary(table)
    out = Path(out)
    files_written["summary"] = out / "fleet_summary.json"
    files_written["summary"].write_text(json.dumps(summary, indent=1))
    files_written["text"] = out / "fleet_summary.txt"
    files_written["text"].write_text(summary_text(summary) + "\n")
    if plots:
        files_written.update(_plots(table, summary, out))
    return FleetResult(out, table, stats, summary, files_written)
