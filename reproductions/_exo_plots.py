"""Figures of the ``exo-lqi`` scenario, laid out like Figs. 13-20 of [1]_.

References
----------
.. [1] Exoskeleton bond graph / Kalman observer paper,
   seed 004 (``docs/references.md``), Section 5.2.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ._exo_analysis import GRID, freqresp

__all__ = ["plot_all"]

MOTOR_TORQUE_LIMIT = 0.56   # N m, Sec. 5.2 of [1]


def _fig(nrows=1, ncols=1, **kw):
    from matplotlib.figure import Figure
    fig = Figure(figsize=kw.pop("figsize", (8, 5)))
    return fig, fig.subplots(nrows, ncols, **kw)


def _nyquist(loop, margins, out: Path) -> Path:
    from matplotlib.patches import Circle

    L = freqresp(*loop, GRID)
    fig, (ax1, ax2) = _fig(1, 2, figsize=(11, 5))
    for ax, lim in ((ax1, None), (ax2, 2.5)):
        ax.plot(L.real, L.imag, "C0", lw=1, label="L(jw), w > 0")
        ax.plot(L.real, -L.imag, "C0--", lw=0.8, label="w < 0")
        ax.plot([-1], [0], "r+", ms=12, mew=2, label="-1")
        ax.set_xlabel("Re L")
        ax.set_ylabel("Im L")
        if lim:
            ax.set_xlim(-lim, lim)
            ax.set_ylim(-lim, lim)
            ax.set_aspect("equal")
            ax.add_patch(Circle((0, 0), 1.0, fill=False, ls=":", color="0.5"))
        ax.grid(True, lw=0.3)
    ax1.set_title("Fig. 13: Nyquist of the loop at the motor-torque input")
    ax2.set_title(f"Fig. 14: near -1 (GM {margins.gain_db:.2f} dB, PM {margins.phase_deg:.1f} deg, "
                  f"DM {1e3 * margins.delay_s:.2f} ms)", fontsize=9)
    ax1.legend(loc="best", fontsize=8)
    fig.tight_layout()
    path = out / "exo_lqi_nyquist.png"
    fig.savefig(path, dpi=110)
    return path


def _bode(dist, band, out: Path) -> Path:
    A, B, C, D = dist
    w = np.logspace(-1, 4.5, 1500)
    H = freqresp(A, B, C[[0]], D[[0]], w)
    fig, (ax1, ax2) = _fig(2, 1, sharex=True, figsize=(8, 6))
    f = w / (2 * np.pi)
    ax1.semilogx(f, 20 * np.log10(np.abs(H)))
    ax1.axhline(20 * np.log10(band.peak_gain) - 3.0, color="0.5", ls=":", label="peak - 3 dB")
    for x in (band.lower_hz, band.upper_hz):
        ax1.axvline(x, color="C3", ls="--", lw=0.8)
    ax1.set_ylabel("|y_b_hat / theta_h_dot| [dB re 1 N m s/rad]")
    ax1.set_title(f"Fig. 15: trunk velocity -> estimated body torque (peak {band.peak_hz:.2f} Hz, "
                  f"-3 dB band {band.lower_hz:.2f}-{band.upper_hz:.2f} Hz)", fontsize=9)
    ax1.legend(fontsize=8)
    ax2.semilogx(f, np.degrees(np.unwrap(np.angle(H))))
    ax2.set_ylabel("phase [deg]")
    ax2.set_xlabel("f [Hz]")
    for ax in (ax1, ax2):
        ax.grid(True, which="both", lw=0.3)
    fig.tight_layout()
    path = out / "exo_lqi_bode.png"
    fig.savefig(path, dpi=110)
    return path


def _two_panel(t, top, bottom, ylabel_top, ylabel_bottom, title, path):
    fig, (ax1, ax2) = _fig(2, 1, sharex=True, figsize=(8, 6))
    for label, y, style in top:
        ax1.plot(t, y, style, lw=1, label=label)
    ax1.set_ylabel(ylabel_top)
    ax1.legend(fontsize=8)
    ax1.set_title(title, fontsize=10)
    ax2.plot(t, bottom, "C3", lw=0.8)
    ax2.set_ylabel(ylabel_bottom)
    ax2.set_xlabel("t [s]")
    for ax in (ax1, ax2):
        ax.grid(True, lw=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    return path


def plot_all(res, loop, margins, dist, band, out) -> list[Path]:
    """Save Figs. 13-20 of [1]_ for the scenario's results in directory `out`.

    Parameters
    ----------
    res : CosimResult
        The co-simulated loop (:func:`._exo_loop.cosimulate`).
    loop, dist : tuple of ndarray
        ``(A, B, C, D)`` of the loop gain and of trunk velocity -> body torque.
    margins : Margins
    band : Bandwidth
    out : path-like

    Returns
    -------
    list of pathlib.Path
    """
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    t = res.t
    yb, ybh = np.asarray(res["plant.tau_b"]), np.asarray(res["ctrl.y_b_hat"])
    wm, wmh = np.asarray(res["sens.w_m_out"]), np.asarray(res["ctrl.w_m_hat"])
    u = np.asarray(res["ctrl.tau_m"])
    paths = [_nyquist(loop, margins, out), _bode(dist, band, out)]
    paths.append(_two_panel(t, [("tau_ref", res["ref.y"], "k--"), ("y_b (plant FMU)", yb, "C0"),
                                ("y_b_hat (observer)", ybh, "C1--")], yb - ybh,
                            "body torque [N m]", "y_b - y_b_hat [N m]",
                            "Figs. 16-17: tau_ref 10 N m at 0.1 s, trunk velocity 0.1 rad/s",
                            out / "exo_lqi_step.png"))
    paths.append(_two_panel(t, [("measured", wm, "C0"), ("estimated", wmh, "C1--")], wm - wmh,
                            "motor velocity [rad/s]", "measured - estimated [rad/s]",
                            "Figs. 18-19: motor velocity", out / "exo_lqi_motor_velocity.png"))
    fig, ax = _fig()
    ax.plot(t, u, lw=1, label="tau_m command")
    for s in (1, -1):
        ax.axhline(s * MOTOR_TORQUE_LIMIT, color="C3", ls="--", lw=0.8)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("motor torque [N m]")
    ax.set_title(f"Fig. 20: motor torque (max |tau_m| {np.max(np.abs(u)):.3f} N m, limit "
                 f"+-{MOTOR_TORQUE_LIMIT} N m)", fontsize=10)
    ax.grid(True, lw=0.3)
    fig.tight_layout()
    path = out / "exo_lqi_motor_torque.png"
    fig.savefig(path, dpi=110)
    paths.append(path)
    return paths
