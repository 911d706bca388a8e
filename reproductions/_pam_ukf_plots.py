"""Plots of scenario ``pam-ukf``, laid out like Figs. 9 and 10 of seed 000.

Each figure: (a) the two pressures (readings, model alone, UKF); (b) the
estimated quantity (truth, model alone, UKF) and (c) its estimation errors.
Colours as in the paper: black the sensor (here the rig's truth), blue the
model alone, red the UKF.
"""
from __future__ import annotations

from pathlib import Path

__all__ = ["save_plots", "FILES"]

#: Figure files written by :func:`save_plots`, by rig variant.
FILES = {"free": "pam_ukf_angle.png", "locked": "pam_ukf_torque.png"}

_QUANTITY = {"free": ("psi", "joint angle $\\psi$ (deg)"), "locked": ("tau", "torque $\\tau$ (N m)")}


def _figure(run: dict, variant: str, t_converge: float):
    from matplotlib.figure import Figure

    t = run["t"]
    signal, label = _QUANTITY[variant]
    fig = Figure(figsize=(9, 9), constrained_layout=True)
    ax_p, ax_q, ax_e = fig.subplots(3, 1, sharex=True)
    for i, name in enumerate(("P1", "P2")):
        ax_p.plot(t, run["z"][:, i] / 1e3, color="0.6", lw=0.4, label=f"{name} reading" if i == 0 else None)
        ax_p.plot(t, run["model"][name] / 1e3, color="tab:blue", lw=0.9, label="model alone" if i == 0 else None)
        ax_p.plot(t, run["ukf"][name] / 1e3, color="tab:red", lw=0.9, label="UKF" if i == 0 else None)
    ax_p.set_ylabel("pressure (kPa abs)")
    ax_p.set_title("(a) pressures P1, P2: noisy readings, model alone, UKF")
    ax_q.plot(t, run["truth"][signal], color="k", lw=1.0, label="rig (truth)")
    ax_q.plot(t, run["model"][signal], color="tab:blue", lw=0.9, label="model alone")
    ax_q.plot(t, run["ukf"][signal], color="tab:red", lw=0.9, label="UKF")
    ax_q.set_ylabel(label)
    ax_q.set_title(f"(b) {label}")
    ax_e.plot(t, run["truth"][signal] - run["model"][signal], color="tab:blue", lw=0.9, label="model alone")
    ax_e.plot(t, run["truth"][signal] - run["ukf"][signal], color="tab:red", lw=0.9, label="UKF")
    ax_e.set_ylabel(f"error, {label.split(' (')[1].rstrip(')')}")
    ax_e.set_title(f"(c) estimation error (indices from t = {t_converge:g} s, dotted)")
    ax_e.set_xlabel("time (s)")
    for ax in (ax_p, ax_q, ax_e):
        ax.axvline(t_converge, color="0.3", ls=":", lw=0.8)
        ax.grid(True, alpha=0.3)
        ax.legend(loc="upper right", fontsize="small")
    return fig


def save_plots(runs: dict, out: Path, *, t_converge: float) -> list[Path]:
    """Write the angle (free joint) and torque (locked joint) figures to `out`.

    Parameters
    ----------
    runs : dict
        ``{"free": ..., "locked": ...}`` as returned by
        :func:`reproductions.pam_ukf.experiment`.
    out : pathlib.Path
        Directory (created if missing).
    t_converge : float, s
        Start of the index window, marked on the plots.

    Returns
    -------
    list of pathlib.Path
        The files written (:data:`FILES`).
    """
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    for variant, run in runs.items():
        path = out / FILES[variant]
        _figure(run, variant, t_converge).savefig(path, dpi=110)
        paths.append(path)
    return paths
