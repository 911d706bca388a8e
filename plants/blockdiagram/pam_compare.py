"""The PAM joint's bond graph (``plants.library.pam``) against its state-space twin (eq. 11a).

Both run the project's fixed-step scheme (1 ms samples, inputs held per
sample, 4 classic RK4 sub-steps of 0.25 ms, friction held per sub-step),
from the same equilibrium, on the same Fig. 8-like input profile.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import pam as bd
from ..errors import ArgumentError

__all__ = ["PamComparison", "compare_fig8", "SIGNALS"]

#: Compared signals: bond-graph output name -> (block-diagram key, label).
SIGNALS = {"psi": ("psi_deg", "angle psi [deg]"), "P1": ("P1", "P1 [Pa]"),
           "P2": ("P2", "P2 [Pa]"), "tau": ("tau", "torque tau [N m]")}


@dataclass(frozen=True)
class PamComparison:
    """Both models on one 1 ms grid.

    Attributes
    ----------
    variant : str
    t : ndarray, shape (n_t,), s
    block_diagram, bond_graph : dict str -> ndarray
        ``psi`` (deg), ``P1``, ``P2`` (Pa), ``tau`` (N m).
    max_abs_error, rms_error : dict str -> float
        Bond graph minus block diagram.
    """

    variant: str
    t: np.ndarray
    block_diagram: dict
    bond_graph: dict
    max_abs_error: dict
    rms_error: dict

    def plot(self, path):
        """Save the overlay (top) and difference (bottom) of the four signals to `path`."""
        from matplotlib.figure import Figure

        fig = Figure(figsize=(14, 6))
        axes = fig.subplots(2, 4, sharex=True)
        for col, (name, (_, label)) in enumerate(SIGNALS.items()):
            ax, axd = axes[0, col], axes[1, col]
            ax.plot(self.t, self.block_diagram[name], label="state space (11a)")
            ax.plot(self.t, self.bond_graph[name], "--", label="bond graph")
            ax.set_ylabel(label)
            ax.legend(loc="best", fontsize=7)
            axd.plot(self.t, self.bond_graph[name] - self.block_diagram[name], color="C3")
            axd.set_ylabel("bond graph - (11a)")
            axd.set_xlabel("t [s]")
        fig.suptitle(f"PAM joint ({self.variant}): bond graph vs state-space model, Fig. 8-like inputs")
        fig.tight_layout()
        fig.savefig(path, dpi=120)
        return path


def compare_fig8(*, variant: str = "full", duration: float = 20.0, segment: float = 2.0) -> PamComparison:
    """Run both models on the first `duration` seconds of :func:`bd.fig8_profile`.

    Parameters
    ----------
    variant : {"full", "frictionless", "locked"}
    duration : float, s
    segment : float, s
        Length of each step/ramp segment of the profile.
    """
    from ..library.pam import pam
    from bondgraph.numerics.simulation import simulate

    _, u = bd.fig8_profile(segment=segment)
    n = int(round(duration / bd.SAMPLE_TIME))
    if n > len(u):
        raise ArgumentError(f"duration {duration} s is longer than the profile ({len(u) * bd.SAMPLE_TIME:g} s)")
    u = u[:n]
    x0 = bd.equilibrium(u[0], variant=variant)
    ref = bd.simulate(u, duration, variant=variant, x0=x0)
    graph = pam(variant)
    init = {"P_1": x0[2], "P_2": x0[3]}
    if variant != "locked":
        init.update(q_psi=x0[0], p_J=x0[1] * graph.equations().param_values["J"])
    samples = np.arange(n) * bd.SAMPLE_TIME
    res = simulate(graph, (0.0, duration), inputs={"u1": (samples, u[:, 0]), "u2": (samples, u[:, 1])},
                   x0=init, output_interval=bd.SAMPLE_TIME, dt=bd.SAMPLE_TIME / bd.SUBSTEPS,
                   method="auto" if variant == "full" else "RK4")
    t = np.asarray(ref["t"])
    block = {name: np.asarray(ref[key]) for name, (key, _) in SIGNALS.items()}
    bond = {name: np.interp(t, res.t, res[name]) for name in SIGNALS}
    err = {name: bond[name] - block[name] for name in SIGNALS}
    return PamComparison(variant, t, block, bond, {k: float(np.max(np.abs(v))) for k, v in err.items()},
                         {k: float(np.sqrt(np.mean(v**2))) for k, v in err.items()})
