"""Numbers of a finished sweep: metric quantiles, parameter sensitivity ranking, grid tables.

Compute apart from draw: :mod:`sweeps.plots` draws these.
"""
from __future__ import annotations

import numpy as np

__all__ = ["QUANTILES", "quantile_table", "sensitivity", "grid_table", "varied_columns", "metric_columns"]

#: Quantiles reported for each metric.
QUANTILES = (0.05, 0.25, 0.5, 0.75, 0.95)


def metric_columns(table, wanted=()) -> list:
    """The ``metric.*`` columns to summarise: `wanted` (without the prefix) if given, else every
    numeric metric column that varies across the ok runs."""
    ok = table[table["status"] == "ok"]
    if wanted:
        return [f"metric.{m}" for m in wanted if f"metric.{m}" in table]
    cols = []
    for c in table.columns:
        if c.startswith("metric.") and ok[c].dtype.kind in "fi":
            v = ok[c].to_numpy(dtype=float)
            v = v[np.isfinite(v)]
            if v.size and np.ptp(v) > 0:
                cols.append(c)
    return cols


def varied_columns(table) -> list:
    """The ``param.*`` columns that take more than one numeric value."""
    return [c for c in table.columns if c.startswith("param.") and table[c].dtype.kind in "fi"
            and table[c].nunique() > 1]


def quantile_table(table, metrics) -> dict:
    """Per metric column: ``n`` (finite ok values), ``mean``, ``std`` and the :data:`QUANTILES` (``q05``...).

    Returns
    -------
    dict str -> dict str -> float
        Keyed by metric name without the ``metric.`` prefix.
    """
    ok = table[table["status"] == "ok"]
    out = {}
    for c in metrics:
        v = ok[c].to_numpy(dtype=float)
        v = v[np.isfinite(v)]
        row = {"n": int(v.size), "mean": float(np.mean(v)) if v.size else float("nan"),
               "std": float(np.std(v, ddof=1)) if v.size > 1 else float("nan")}
        row.update({f"q{int(round(100 * q)):02d}": float(np.quantile(v, q)) if v.size else float("nan")
                    for q in QUANTILES})
        out[c.removeprefix("metric.")] = row
    return out


def sensitivity(table, metrics, params) -> list:
    """Spearman rank correlation of each metric with each varied parameter, strongest first.

    .. math:: \\rho_s = \\mathrm{corr}(\\mathrm{rank}(p), \\mathrm{rank}(m))

    over the ok runs with finite values; a monotone effect of any shape gives
    :math:`|\\rho_s|` near 1, no effect near 0.

    Returns
    -------
    list of dict
        ``{"metric", "param", "spearman", "n"}``, sorted by ``|spearman|`` descending within each
        metric, metrics in the given order.
    """
    from scipy.stats import spearmanr
    ok = table[table["status"] == "ok"]
    out = []
    for m in metrics:
        rows = []
        for p in params:
            x, y = ok[p].to_numpy(dtype=float), ok[m].to_numpy(dtype=float)
            keep = np.isfinite(x) & np.isfinite(y)
            rho = float("nan")
            if keep.sum() >= 3 and np.ptp(x[keep]) > 0 and np.ptp(y[keep]) > 0:
                rho = float(spearmanr(x[keep], y[keep]).statistic)
            rows.append({"metric": m.removeprefix("metric."), "param": p.removeprefix("param."),
                         "spearman": rho, "n": int(keep.sum())})
        rows.sort(key=lambda r: -abs(r["spearman"]) if np.isfinite(r["spearman"]) else 1.0)
        out.extend(rows)
    return out


def grid_table(table, metric: str, x: str, y: str):
    """Mean of `metric` over ok runs at each ``(y, x)`` grid point (averaging any other axes).

    Returns
    -------
    xs, ys : ndarray
        The axis values, sorted.
    values : ndarray, shape (len(ys), len(xs))
        NaN where no run succeeded.
    """
    ok = table[table["status"] == "ok"]
    xs, ys = np.sort(table[x].unique()), np.sort(table[y].unique())
    values = np.full((ys.size, xs.size), np.nan)
    means = ok.groupby([y, x])[metric].mean()
    for (yv, xv), v in means.items():
        values[np.searchsorted(ys, yv), np.searchsorted(xs, xv)] = v
    return xs, ys, values
