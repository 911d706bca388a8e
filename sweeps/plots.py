"""Pictures of a finished sweep: metric histograms with quantiles, metric-vs-parameter scatter with
the sensitivity ranking, heat maps over grids.  Numbers come from :mod:`sweeps.summary`."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from .summary import grid_table

__all__ = ["save_plots", "metric_groups"]

_MAX = 6   # metrics (rows) and parameters (columns) drawn at most


def metric_groups(metrics) -> list:
    """Metrics grouped to share a histogram: those equal but for their first part
    (``ukf.angle.I`` with ``model_only.angle.I``: the UKF against the model alone).

    Examples
    --------
    >>> metric_groups(["metric.ukf.angle.I", "metric.model_only.angle.I", "metric.bandwidth_hz"])
    [['metric.ukf.angle.I', 'metric.model_only.angle.I'], ['metric.bandwidth_hz']]
    """
    groups, seen = [], {}
    for m in metrics:
        parts = m.removeprefix("metric.").split(".")
        key = ".".join(parts[1:]) if len(parts) > 1 else m
        if key in seen:
            groups[seen[key]].append(m)
        else:
            seen[key] = len(groups)
            groups.append([m])
    return groups


def _hist(table, metrics, path: Path) -> Path:
    import matplotlib.pyplot as plt
    ok = table[table["status"] == "ok"]
    groups = metric_groups(metrics)[:_MAX]
    fig, axes = plt.subplots(len(groups), 1, figsize=(7, 2.4 * len(groups) + 0.6), squeeze=False)
    for ax, group in zip(axes[:, 0], groups):
        values = [ok[m].to_numpy(dtype=float) for m in group]
        values = [v[np.isfinite(v)] for v in values]
        for m, v in zip(group, values):
            if not v.size:
                continue
            bins = min(30, max(5, v.size // 3))     # each metric over its own range (they may lie far apart)
            q05, q50, q95 = np.quantile(v, [0.05, 0.5, 0.95])
            patch = ax.hist(v, bins=bins, alpha=0.55, label=f"{m.removeprefix('metric.')}: median {q50:.3g} "
                                                         f"(5-95 %: {q05:.3g}-{q95:.3g})")[2]
            color = patch[0].get_facecolor() if len(patch) else None
            ax.axvline(q50, color=color, lw=1.5)
            ax.axvspan(q05, q95, color=color, alpha=0.08)
        ax.set_ylabel("runs")
        ax.legend(fontsize=7, loc="upper right")
    axes[-1, 0].set_xlabel("metric value (unit of the metric)")
    fig.suptitle(f"{len(ok)} ok runs of {len(table)}: histograms, median (line), 5-95 % band")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def _scatter(table, metrics, params, ranking, units, path: Path) -> Path:
    import matplotlib.pyplot as plt
    ok, bad = table[table["status"] == "ok"], table[table["status"] != "ok"]
    metrics, params = metrics[:_MAX], params[:_MAX]
    rho = {(r["metric"], r["param"]): r["spearman"] for r in ranking}
    fig, axes = plt.subplots(len(metrics), len(params), figsize=(3.0 * len(params) + 0.5, 2.4 * len(metrics) + 0.6),
                             squeeze=False)
    for i, m in enumerate(metrics):
        for j, p in enumerate(params):
            ax = axes[i, j]
            ax.plot(ok[p], ok[m], ".", ms=4, alpha=0.7)
            if len(bad):
                y0 = np.nanmin(ok[m]) if len(ok) else 0.0
                ax.plot(bad[p], np.full(len(bad), y0), "x", color="tab:red", ms=5, label="failed")
            r = rho.get((m.removeprefix("metric."), p.removeprefix("param.")), float("nan"))
            ax.set_title(f"Spearman {r:+.2f}", fontsize=8)
            if i == len(metrics) - 1:
                ax.set_xlabel(_label(p, units), fontsize=8)
            if j == 0:
                ax.set_ylabel(m.removeprefix("metric."), fontsize=8)
            ax.tick_params(labelsize=7)
    fig.suptitle("metric against each varied parameter (failed runs: red x)")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def _label(column: str, units: dict) -> str:
    name = column.removeprefix("param.")
    return f"{name} ({units[name]})" if units.get(name) else name


def _heatmap(table, metric, x, y, units, path: Path) -> Path:
    import matplotlib.pyplot as plt
    xs, ys, values = grid_table(table, metric, x, y)
    fig, ax = plt.subplots(figsize=(6, 4.5))
    mesh = ax.imshow(values, origin="lower", aspect="auto", cmap="viridis")
    ax.set_xticks(range(xs.size), [f"{v:.3g}" for v in xs], fontsize=7, rotation=45)
    ax.set_yticks(range(ys.size), [f"{v:.3g}" for v in ys], fontsize=7)
    ax.set_xlabel(_label(x, units))
    ax.set_ylabel(_label(y, units))
    for (r, c), v in np.ndenumerate(values):
        ax.text(c, r, "failed" if np.isnan(v) else f"{v:.3g}", ha="center", va="center", fontsize=6, color="w")
    fig.colorbar(mesh, ax=ax, label=metric.removeprefix("metric."))
    ax.set_title(f"{metric.removeprefix('metric.')} over the grid (mean of ok runs)")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def save_plots(table, directory, *, metrics, params, grid_params=(), ranking=(), units=None) -> dict:
    """Write the sweep's plots into `directory`.

    Parameters
    ----------
    table : pandas.DataFrame
        The sweep's rows (``runs.parquet``).
    metrics, params : list of str
        ``metric.*`` and ``param.*`` columns to draw.
    grid_params : sequence of str
        ``param.*`` columns that are grid axes; two or more give heat maps (first two axes).
    ranking : list of dict
        :func:`sweeps.summary.sensitivity`, for the scatter titles.
    units : dict str -> str, optional
        Parameter units (names without ``param.``), for the axis labels.

    Returns
    -------
    dict str -> pathlib.Path
        ``histograms``, ``sensitivity`` and ``heatmap:METRIC`` files written.
    """
    import matplotlib
    matplotlib.use("Agg")
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    written = {}
    if not metrics or not (table["status"] == "ok").any():
        return written
    written["histograms"] = _hist(table, metrics, directory / "metrics_histograms.png")
    if params:
        written["sensitivity"] = _scatter(table, metrics, params, ranking, dict(units or {}),
                                          directory / "sensitivity.png")
    if len(grid_params) >= 2:
        for m in metrics[:4]:
            name = m.removeprefix("metric.").replace(".", "_")
            written[f"heatmap:{m}"] = _heatmap(table, m, grid_params[0], grid_params[1], dict(units or {}),
                                               directory / f"heatmap_{name}.png")
    return written
