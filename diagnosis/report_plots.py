"""The report's figures: residual over time with the windows, residual against the
regime variable, measured / nominal / improved on the held-out part (under the segment judge,
:mod:`diagnosis.segments`, the segment simulations, so that a drifting nominal's accumulated
drift does not dominate the plot)."""
from __future__ import annotations

import os

__all__ = ["save_plots"]


def _figure(n_rows):
    import matplotlib
    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(n_rows, 1, figsize=(9, 2.6 * n_rows + 0.6), squeeze=False, sharex=False)
    return plt, fig, axes[:, 0]


def _label(name, units):
    unit = units.get(name, "")
    return f"{name} ({unit})" if unit else name


def save_plots(report, directory) -> dict:
    """Write ``residual_time.png``, ``residual_regime.png`` (when a regime was found)
    and ``holdout_fit.png`` into `directory`; returns their paths by name."""
    data = report.plot_data
    outputs = list(data.measured)
    paths = {}

    plt, fig, axes = _figure(len(outputs))
    for ax, o in zip(axes, outputs):
        ax.plot(data.t, data.measured[o] - data.nominal[o], lw=0.7, label="measured - nominal")
        for i, (a, b) in enumerate(report.location.get("windows", [])):
            ax.axvspan(a, b, color="tab:red", alpha=0.15, label="significant" if i == 0 else None)
        ax.axvline(data.holdout_start, color="k", ls="--", lw=0.8, label="held-out part starts")
        ax.set_ylabel(f"residual {_label(o, data.units)}")
        ax.legend(loc="upper right", fontsize=8)
    axes[-1].set_xlabel("t (s)")
    fig.suptitle("Residual of the nominal model over time")
    fig.tight_layout()
    paths["residual_time"] = os.path.join(directory, "residual_time.png")
    fig.savefig(paths["residual_time"], dpi=110)
    plt.close(fig)

    if data.regime_values is not None and data.regime_signal is not None:
        plt, fig, axes = _figure(1)
        ax = axes[0]
        step = max(1, data.regime_values.size // 20000)
        ax.plot(data.regime_values[::step], data.regime_signal[::step], ".", ms=2, alpha=0.5)
        ax.set_xlabel(data.regime_name or "regime variable")
        ax.set_ylabel(data.regime_label)
        ax.set_title(report.location.get("regime", ""), fontsize=9)
        fig.tight_layout()
        paths["residual_regime"] = os.path.join(directory, "residual_regime.png")
        fig.savefig(paths["residual_regime"], dpi=110)
        plt.close(fig)

    plt, fig, axes = _figure(len(outputs))
    held = data.t >= data.holdout_start
    segments = data.judge == "segments" and data.nominal_segments is not None
    nominal = data.nominal_segments if segments else {o: data.nominal[o][held] for o in outputs}
    improved = data.improved_segments if segments else {o: data.improved[o][held] for o in outputs}
    what = "segment" if segments else "held-out"
    for ax, o in zip(axes, outputs):
        t = data.t[held]
        ax.plot(t, data.measured[o][held], color="0.4", lw=0.8, label="measured")
        ax.plot(t, nominal[o], lw=1.0, label=f"nominal ({what} NRMSE {report.fit['nominal'][o]:.3g})")
        ax.plot(t, improved[o], lw=1.0, ls="--",
                label=f"improved ({what} NRMSE {report.fit['improved'][o]:.3g})")
        for i, start in enumerate(data.segment_starts if segments else []):
            ax.axvline(start, color="0.7", lw=0.6, ls=":", label="segment starts" if i == 0 else None)
        ax.set_ylabel(_label(o, data.units))
        ax.legend(loc="upper right", fontsize=8)
    axes[-1].set_xlabel("t (s)")
    title = f"Held-out part: before / after ({report.kind})"
    if segments:
        title += ": segment simulations, each restarted from a state estimated on its first samples"
    fig.suptitle(title, fontsize=10 if segments else None)
    fig.tight_layout()
    paths["holdout_fit"] = os.path.join(directory, "holdout_fit.png")
    fig.savefig(paths["holdout_fit"], dpi=110)
    plt.close(fig)
    return paths
