"""The exoskeleton's block-diagram model, eqs. (1)-(6) of [1]_, written from the paper.

Independent of the bond graph in :mod:`plants.library.exoskeleton`: the
matrices are typed in from the paper's equations, in the paper's state order

.. math::

    x = [\\theta_m, \\dot\\theta_m, \\theta_{sint}, \\dot\\theta_{sint},
         \\theta_{sext}, \\dot\\theta_{sext}, \\theta_h]^T, \\qquad
    u = [\\tau_m, \\dot\\theta_h]^T, \\qquad
    y = [y_t, y_v, y_b, \\theta_h]^T

with :math:`\\dot x = A x + B u`, :math:`y = C x + D u` (eq. (3), outputs
eqs. (5)-(6)).  Only the comparison helpers at the end
(:func:`bond_graph_state_map`, :func:`compare_section_5_1`) know the bond
graph's state names.

References
----------
.. [1] Exoskeleton bond graph / Kalman observer paper, seed 004 (``docs/references.md``).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping

import numpy as np

from ..errors import ArgumentError, ParameterError

__all__ = ["STATES", "INPUTS", "OUTPUTS", "PARAMETER_NAMES", "state_space", "simulate_zoh", "matrix_difference",
           "section_5_1_inputs", "bond_graph_state_map", "compare_section_5_1", "Comparison", "compare_plot"]

STATES = ("theta_m", "dtheta_m", "theta_sint", "dtheta_sint", "theta_sext", "dtheta_sext", "theta_h")
INPUTS = ("tau_m", "w_h")
OUTPUTS = ("tau_s", "w_m", "tau_b", "theta_h")
PARAMETER_NAMES = ("J_m", "J_g", "b_f", "r_g", "b_g", "k_g", "d_g", "J_sint", "k_s", "d_s", "J_sext",
                   "k_eh", "d_eh")


def _check(params: Mapping[str, float]) -> dict[str, float]:
    missing = [n for n in PARAMETER_NAMES if n not in params]
    if missing:
        raise ParameterError(f"exoskeleton block diagram: missing parameter(s) {', '.join(missing)}; "
                             f"expected {', '.join(PARAMETER_NAMES)}", name=missing[0])
    return {n: float(params[n]) for n in PARAMETER_NAMES}


def state_space(params: Mapping[str, float], *, b_g_exponent: int = 2):
    """Matrices of eq. (3) (plus outputs eqs. (5)-(6)) of [1]_.

    .. math::

        J_1 \\ddot\\theta_m &= \\tau_m - b_f\\dot\\theta_m - \\frac{b_g}{r_g^n}\\dot\\theta_m
            - \\frac{k_g}{r_g}\\Big(\\frac{\\theta_m}{r_g} - \\theta_{sint}\\Big)
            - \\frac{d_g}{r_g}\\Big(\\frac{\\dot\\theta_m}{r_g} - \\dot\\theta_{sint}\\Big),
            \\quad J_1 = J_m + J_g \\\\
        J_{sint}\\ddot\\theta_{sint} &= k_g\\Big(\\frac{\\theta_m}{r_g} - \\theta_{sint}\\Big)
            + d_g\\Big(\\frac{\\dot\\theta_m}{r_g} - \\dot\\theta_{sint}\\Big)
            - k_s(\\theta_{sint} - \\theta_{sext}) - d_s(\\dot\\theta_{sint} - \\dot\\theta_{sext}) \\\\
        J_{sext}\\ddot\\theta_{sext} &= k_s(\\theta_{sint} - \\theta_{sext})
            + d_s(\\dot\\theta_{sint} - \\dot\\theta_{sext})
            - k_{eh}(\\theta_{sext} - \\theta_h) - d_{eh}(\\dot\\theta_{sext} - \\dot\\theta_h) \\\\
        \\dot\\theta_h &= u_2, \\quad
        y_t = k_s(\\theta_{sint} - \\theta_{sext}) + d_s(\\dot\\theta_{sint} - \\dot\\theta_{sext}), \\quad
        y_v = \\dot\\theta_m, \\quad
        y_b = k_{eh}(\\theta_{sext} - \\theta_h) + d_{eh}(\\dot\\theta_{sext} - \\dot\\theta_h)

    Parameters
    ----------
    params : mapping str -> float
        SI values of :data:`PARAMETER_NAMES` (extra names are ignored).
    b_g_exponent : {1, 2}
        ``n`` in the gearbox-friction term ``b_g / r_g**n``: 2 as in the
        matrix eq. (3) (the default, and what the bond graph implies), 1 as
        printed in eq. (1).

    Returns
    -------
    A : ndarray, shape (7, 7), B : ndarray, shape (7, 2), C : ndarray, shape (4, 7), D : ndarray, shape (4, 2)
    """
    if b_g_exponent not in (1, 2):
        raise ArgumentError(f"b_g_exponent must be 1 or 2, got {b_g_exponent!r}")
    p = _check(params)
    J1, r = p["J_m"] + p["J_g"], p["r_g"]
    kg, dg, ks, ds, keh, deh = p["k_g"], p["d_g"], p["k_s"], p["d_s"], p["k_eh"], p["d_eh"]
    Js, Je = p["J_sint"], p["J_sext"]
    A = np.zeros((7, 7))
    A[0, 1] = A[2, 3] = A[4, 5] = 1.0
    # row 2 of eq. (3); with n = 2: -(b_f r_g^2 + b_g + d_g) / (J1 r_g^2)
    A[1, :4] = [-kg / (J1 * r**2), -(p["b_f"] + p["b_g"] / r**b_g_exponent + dg / r**2) / J1,
                kg / (J1 * r), dg / (J1 * r)]
    A[3, :6] = [kg / (Js * r), dg / (Js * r), -(kg + ks) / Js, -(dg + ds) / Js, ks / Js, ds / Js]
    A[5, 2:] = [ks / Je, ds / Je, -(keh + ks) / Je, -(deh + ds) / Je, keh / Je]
    # row 7 is zero: theta_h' is the input
    B = np.zeros((7, 2))
    B[1, 0] = 1.0 / J1
    B[5, 1] = deh / Je
    B[6, 1] = 1.0
    C = np.array([[0, 0, ks, ds, -ks, -ds, 0],          # y_t, eq. (5)
                  [0, 1, 0, 0, 0, 0, 0],                # y_v, eq. (5)
                  [0, 0, 0, 0, keh, deh, -keh],         # y_b, eqs. (6)-(7)
                  [0, 0, 0, 0, 0, 0, 1]], dtype=float)
    D = np.zeros((4, 2))
    D[2, 1] = -deh                                      # y_b's -d_eh theta_h' term, eq. (6)
    return A, B, C, D


def simulate_zoh(A, B, C, D, t, u, *, x0=None):
    """Exact discretisation with zero-order-hold inputs.

    .. math::

        \\exp\\Big(\\begin{bmatrix} A & B \\\\ 0 & 0 \\end{bmatrix} \\Delta t\\Big)
        = \\begin{bmatrix} A_d & B_d \\\\ 0 & I \\end{bmatrix}, \\quad
        x_{k+1} = A_d x_k + B_d u_k, \\quad y_k = C x_k + D u_k

    Exact for inputs constant on each interval, so the fast mode (about
    -5e4 1/s) costs nothing in accuracy or stability.

    Parameters
    ----------
    A, B, C, D : ndarray
        Continuous-time matrices.
    t : ndarray, shape (n_t,), s
        Uniformly spaced sample times.
    u : ndarray, shape (n_t, n_inputs)
        Input held over ``[t_k, t_k+1)``.
    x0 : ndarray, shape (n_states,), optional
        Initial state (default 0).

    Returns
    -------
    y : ndarray, shape (n_t, n_outputs)
    x : ndarray, shape (n_t, n_states)
    """
    from scipy.linalg import expm

    t = np.asarray(t, dtype=float)
    u = np.asarray(u, dtype=float).reshape(len(t), -1)
    dt = np.diff(t)
    if len(t) < 2 or not np.allclose(dt, dt[0], rtol=1e-9, atol=0.0) or dt[0] <= 0:
        raise ArgumentError("simulate_zoh: t must hold at least two uniformly increasing sample times")
    n, m = B.shape
    M = np.zeros((n + m, n + m))
    M[:n, :n], M[:n, n:] = A, B
    E = expm(M * dt[0])
    Ad, Bd = E[:n, :n], E[:n, n:]
    x = np.zeros((len(t), n))
    x[0] = 0.0 if x0 is None else x0
    for k in range(len(t) - 1):
        x[k + 1] = Ad @ x[k] + Bd @ u[k]
    return x @ C.T + u @ D.T, x


def section_5_1_inputs(t, *, tau_m: float = 0.1, w_h: float = 0.05, delay: float = 0.1):
    """Sec. 5.1 of [1]_: ``tau_m`` (N m) from 0 and ``w_h`` (rad/s) from `delay` (s).

    Returns ndarray, shape (n_t, 2).  A sample at exactly `delay` already
    carries the step (up to 1e-12 s of rounding in `t`).
    """
    t = np.asarray(t, dtype=float)
    return np.column_stack([np.full_like(t, tau_m), np.where(t >= delay - 1e-12, w_h, 0.0)])


def bond_graph_state_map(params: Mapping[str, float]) -> np.ndarray:
    """T with ``x_paper = T x_bg`` for the states of :func:`plants.library.exoskeleton.exoskeleton`.

    Bond-graph states ``(p_J_m, q_k_g, p_J_sint, q_k_s, p_J_sext, q_k_eh,
    q_theta_h)``: ``theta_h = q_theta_h``, ``theta_sext = q_k_eh + theta_h``,
    ``theta_sint = q_k_s + theta_sext``, ``theta_m = r_g (q_k_g + theta_sint)``,
    velocities ``p / J`` (after eliminating ``J_g`` the motor momentum is
    ``p_J_m = J_m w_m``).
    """
    p = _check(params)
    T = np.zeros((7, 7))
    T[6, 6] = 1.0
    T[4] = T[6] + np.eye(7)[5]
    T[2] = T[4] + np.eye(7)[3]
    T[0] = p["r_g"] * (T[2] + np.eye(7)[1])
    T[1, 0], T[3, 2], T[5, 4] = 1 / p["J_m"], 1 / p["J_sint"], 1 / p["J_sext"]
    return T


@dataclass(frozen=True)
class Comparison:
    """Sec. 5.1 run of both models on a common grid.

    Attributes
    ----------
    t : ndarray, shape (n_t,), s
    block_diagram, bond_graph : dict str -> ndarray, shape (n_t,)
        ``tau_s`` (N m) and ``w_m`` (rad/s) of each model.
    max_abs_error, rms_error : dict str -> float
        Bond graph minus block diagram, per signal.
    """

    t: np.ndarray
    block_diagram: dict
    bond_graph: dict
    max_abs_error: dict
    rms_error: dict

    def plot(self, path):
        """Save the Figs. 10-11-like overlay and difference plot to `path`."""
        return compare_plot(self.t, self.block_diagram, self.bond_graph, path)


def compare_section_5_1(*, params: Mapping[str, float] | None = None, t_end: float = 1.0,
                        dt: float = 1e-4) -> Comparison:
    """Run Sec. 5.1 on the bond graph (Radau) and the block diagram (exact ZOH).

    Parameters
    ----------
    params : mapping str -> float, optional
        Overrides of the library parameters; default ``{"b_f": 0.0}``, the
        paper's simulation setting (Sec. 4 neglects b_f).
    t_end, dt : float, s
        Horizon and sample spacing.
    """
    from ..library.exoskeleton import exoskeleton, parameter_values
    from bondgraph.numerics.simulation import simulate

    overrides = {"b_f": 0.0} if params is None else dict(params)
    values = parameter_values(overrides)
    n = int(round(t_end / dt))
    t = np.linspace(0.0, n * dt, n + 1)
    A, B, C, D = state_space(values)
    y, _ = simulate_zoh(A, B, C, D, t, section_5_1_inputs(t))
    bd = {"tau_s": y[:, 0], "w_m": y[:, 1]}
    # Radau (implicit) for the fast mode near -5e4 1/s; max_step 1 ms keeps it from stepping
    # across the trunk-velocity step at 0.1 s unseen
    res = simulate(exoskeleton(params=overrides), (0.0, t[-1]), method="Radau", output_interval=dt, dt=1e-3,
                   inputs={"tau_m": 0.1, "w_h": "0.05*Heaviside(t - 0.1, 1)"}, rtol=1e-10, atol=1e-12)
    bg = {k: np.interp(t, np.asarray(res.t), np.asarray(res[k])) for k in bd}
    err = {k: bg[k] - bd[k] for k in bd}
    return Comparison(t, bd, bg, {k: float(np.max(np.abs(v))) for k, v in err.items()},
                      {k: float(np.sqrt(np.mean(v**2))) for k, v in err.items()})


def matrix_difference(params: Mapping[str, float] | None = None) -> float:
    """Largest relative difference between the bond graph's (A, B, C, D) and eq. (3).

    The bond graph is linearised and mapped to the paper's states with
    :func:`bond_graph_state_map` (``A_paper = T A_bg T^-1``, ``B = T B_bg``,
    ``C = C_bg T^-1``).  Entries that are zero in eq. (3) are measured
    against the matrix's largest entry.
    """
    from ..library.exoskeleton import exoskeleton, parameter_values

    overrides = dict(params or {})
    lm = exoskeleton(params=overrides).equations().linearize()
    values = parameter_values(overrides)
    T = bond_graph_state_map(values)
    Ti = np.linalg.solve(T, np.eye(T.shape[0]))
    mapped = (T @ lm.A @ Ti, T @ lm.B, lm.C @ Ti, lm.D)
    worst = 0.0
    for ref, other in zip(state_space(values), mapped):
        scale = np.where(ref != 0, np.abs(ref), np.max(np.abs(ref)) if ref.any() else 1.0)
        worst = max(worst, float(np.max(np.abs(other - ref) / scale)))
    return worst


def compare_plot(t, block_diagram: Mapping[str, np.ndarray], bond_graph: Mapping[str, np.ndarray], path):
    """Overlay (top) and difference (bottom) of sensor torque and motor velocity, like Figs. 10-11 of [1]_.

    Parameters
    ----------
    t : ndarray, shape (n_t,), s
    block_diagram, bond_graph : mapping str -> ndarray, shape (n_t,)
        ``tau_s`` (N m) and ``w_m`` (rad/s).
    path : str or path-like
        Output file (format from the suffix).

    Returns
    -------
    pathlib.Path
    """
    from pathlib import Path

    from matplotlib.figure import Figure

    labels = {"tau_s": "sensor torque y_t [N m]", "w_m": "motor velocity [rad/s]"}
    fig = Figure(figsize=(11, 6))
    axes = fig.subplots(2, 2, sharex=True)
    for col, key in enumerate(("tau_s", "w_m")):
        ax, axd = axes[0, col], axes[1, col]
        ax.plot(t, block_diagram[key], label="block diagram (eq. 3, exact ZOH)")
        ax.plot(t, bond_graph[key], "--", label="bond graph (Fig. 6, Radau)")
        ax.set_ylabel(labels[key])
        ax.legend(loc="best", fontsize=8)
        axd.plot(t, np.asarray(bond_graph[key]) - np.asarray(block_diagram[key]), color="C3")
        axd.set_ylabel("bond graph - block diagram")
        axd.set_xlabel("t [s]")
    fig.suptitle("Exoskeleton, Sec. 5.1: tau_m = 0.1 N m, trunk velocity 0.05 rad/s from 0.1 s")
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path)
    return path
