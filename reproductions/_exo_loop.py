"""The sampled ``exo-lqi`` closed loop, twice: in the co-simulation master
around the exoskeleton FMU (:func:`cosimulate`) and as one linear
discrete-time system (:func:`monolithic`), the reference the co-simulation is
checked against.

Per sample ``k`` (period ``dt``, Fig. 12 of [1]_)::

    y_k      = [w_m, tau_s](t_k) + [v_v, v_t]_k                    sensors, eq. (5)
    x+_k     = x-_k + K (y_k - C_m x-_k)                           Kalman update
    u_k      = -F'_ix x+_k - F'_iz z_k - F_iz w_k                  eq. (13)
    plant:   tau_m = u_k + w_tau_k, theta_h_dot = v_h + w_h_k, held over [t_k, t_k+1)
    x-_k+1   = F x+_k + G_d [u_k, v_h]                             Kalman predict (ZOH model)
    w_k+1    = w_k + dt z_k,  z_k+1 = z_k + dt (tau_ref_k - y_b_hat_k)   eqs. (10), (12)

with ``y_b_hat = C_b x+ - d_eh v_h`` (eq. (6)) and ``v_h`` the nominal trunk
velocity, a known input of the observer (eq. (8)).

References
----------
.. [1] Exoskeleton bond graph / Kalman observer paper,
   seed 004 (``docs/references.md``), Section 5.2.
"""
from __future__ import annotations

import numpy as np

from plants.blockdiagram.exoskeleton import state_space
from .errors import CosimError

from cosim.blocks import Constant, Step
from cosim.component import Port, PythonBlock
from cosim.fmu_component import FMUComponent
from cosim.master import CoSimulation
from ._exo_design import ExoDesign

__all__ = ["ObserverLQI", "AddNoise", "cosimulate", "monolithic", "NOISE_COLUMNS"]

#: Columns of the noise array: motor-torque, trunk-velocity (process), encoder, torque-sensor (measurement).
NOISE_COLUMNS = ("tau_m", "w_h", "w_m", "tau_s")
_UNITS = {"tau_m": "N m", "w_h": "rad/s", "w_m": "rad/s", "tau_s": "N m"}


class ObserverLQI(PythonBlock):
    """Kalman observer + LQI with double integral action (module docstring) as one block.

    Inputs ``tau_ref`` (N m), ``w_h`` (nominal trunk velocity, rad/s), ``w_m``
    (measured motor velocity, rad/s), ``tau_s`` (measured sensor torque, N m);
    outputs ``tau_m`` (motor-torque command, N m), ``y_b_hat`` (estimated body
    torque, N m), ``w_m_hat`` (estimated motor velocity, rad/s).  The state is
    committed in :meth:`advance`, so :meth:`output` may run twice at a time.

    Parameters
    ----------
    name : str
    design : ExoDesign
    """

    def __init__(self, name: str, design: ExoDesign):
        super().__init__(name, inputs=[Port("tau_ref", "N m", "body-torque reference"),
                                       Port("w_h", "rad/s", "nominal trunk velocity"),
                                       Port("w_m", "rad/s", "measured motor velocity"),
                                       Port("tau_s", "N m", "measured sensor torque")],
                         outputs=[Port("tau_m", "N m", "motor-torque command"),
                                  Port("y_b_hat", "N m", "estimated body torque"),
                                  Port("w_m_hat", "rad/s", "estimated motor velocity")])
        self.d = design
        g = design.lqi2
        self._k = np.hstack([g.Kx, g.Kz, g.Kzz])[0]
        self.start(0.0)

    def start(self, t0: float) -> None:
        self.x_prior, self.z, self.w = np.zeros(6), 0.0, 0.0

    def _posterior(self):
        d = self.d
        y = self.u[2:4]
        x_post = self.x_prior + d.observer_d.K @ (y - d.Cm @ self.x_prior)
        u = -float(self._k @ np.concatenate([x_post, [self.z, self.w]]))
        y_b_hat = float(d.Cb[0] @ x_post) - d.d_eh * self.u[1]
        return x_post, u, y_b_hat

    def output(self, t: float) -> None:
        x_post, u, y_b_hat = self._posterior()
        self.y[0], self.y[1], self.y[2] = u, y_b_hat, x_post[1]

    def advance(self, t: float, dt: float) -> None:
        d = self.d
        x_post, u, y_b_hat = self._posterior()
        self.x_prior = d.F @ x_post + d.Gd @ np.array([u, self.u[1]])
        self.w = self.w + d.dt * self.z
        self.z = self.z + d.dt * (self.u[0] - y_b_hat)


class AddNoise(PythonBlock):
    """``s_out = s + noise[k, i]`` (input ``s``, output ``s_out``) with ``k = round((t - t0) / dt)`` (noise held over each sample).

    Parameters
    ----------
    name : str
    signals : sequence of str
        Signal names (input ``s``, output ``s_out``) with units from :data:`NOISE_COLUMNS`.
    noise : ndarray, shape (n_samples, len(signals))
    dt : float, s
    """

    def __init__(self, name: str, signals, noise, dt: float):
        signals = tuple(signals)
        unknown = [s for s in signals if s not in _UNITS]
        if unknown:
            raise CosimError(f"block {name!r}: unknown signal(s) {', '.join(unknown)}; expected some of "
                             f"{', '.join(NOISE_COLUMNS)}")
        noise = np.asarray(noise, dtype=float)
        if noise.ndim != 2 or noise.shape[1] != len(signals) or noise.shape[0] == 0:
            raise CosimError(f"block {name!r}: noise must have shape (n_samples, {len(signals)}); "
                             f"found {noise.shape}")
        super().__init__(name, inputs=[Port(s, _UNITS[s]) for s in signals],
                         outputs=[Port(f"{s}_out", _UNITS[s], f"{s} plus noise") for s in signals],
                         feedthrough=[(s, f"{s}_out") for s in signals])
        self.noise, self.dt, self.t0 = np.asarray(noise, dtype=float), float(dt), 0.0

    def start(self, t0: float) -> None:
        self.t0 = t0

    def output(self, t: float) -> None:
        k = min(int(round((t - self.t0) / self.dt)), self.noise.shape[0] - 1)
        self.y[:] = self.u + self.noise[k]


def cosimulate(design: ExoDesign, fmu, *, t_end: float, noise, w_h: float, tau_ref: float, t_ref: float,
               params=None):
    """The loop in the master: exoskeleton FMU, noise, observer + LQI.

    Parameters
    ----------
    design : ExoDesign
    fmu : path-like
        The exoskeleton FMU (inputs ``tau_m``, ``w_h``; outputs ``tau_s``, ``w_m``, ``tau_b``).
    t_end : float, s
    noise : ndarray, shape (n + 1, 4)
        Columns :data:`NOISE_COLUMNS`, sample ``k`` at ``t_k = k dt``.
    w_h : float, rad/s
        Constant trunk velocity (Sec. 5.2: 0.1).
    tau_ref, t_ref : float, N m and s
        Reference step (Sec. 5.2: 10 N m at 0.1 s).
    params : mapping str -> float, optional
        FMU parameter values (SI) set before initialisation (default: the FMU's own).

    Returns
    -------
    CosimResult
        ``plant.*`` (true signals), ``ctrl.tau_m``, ``ctrl.y_b_hat``, ``ctrl.w_m_hat``,
        ``sens.*_out`` (measurements), ``act.*_out`` (plant inputs).
    """
    noise = np.asarray(noise, dtype=float)
    blocks = [Step("ref", t_ref, 0.0, tau_ref, "N m"), Constant("trunk", w_h, "rad/s"),
              AddNoise("act", ("tau_m", "w_h"), noise[:, :2], design.dt),
              AddNoise("sens", ("w_m", "tau_s"), noise[:, 2:], design.dt),
              ObserverLQI("ctrl", design), FMUComponent(fmu, "plant", parameters=params)]
    sim = CoSimulation(blocks, [
        ("ref.y", "ctrl.tau_ref"), ("trunk.y", "ctrl.w_h"), ("trunk.y", "act.w_h"),
        ("ctrl.tau_m", "act.tau_m"), ("act.tau_m_out", "plant.tau_m"), ("act.w_h_out", "plant.w_h"),
        ("plant.w_m", "sens.w_m"), ("plant.tau_s", "sens.tau_s"),
        ("sens.w_m_out", "ctrl.w_m"), ("sens.tau_s_out", "ctrl.tau_s")], step=design.dt)
    return sim.run(t_end)


def _closed_loop_matrices(d: ExoDesign):
    """One discrete system: states ``[x_plant (7, eq. (3)), x_prior (6), z, w]``, inputs
    ``[tau_ref, v_h, w_tau, w_h, v_v, v_t]``, outputs ``[u, y_b_hat, w_m_hat, y_b, w_m, tau_s]``."""
    from scipy.signal import cont2discrete

    A, B, C, D = state_space(d.params)                    # the paper's absolute 7-state plant
    Ad, Bd, *_ = cont2discrete((A, B, C, D), d.dt, method="zoh")
    K, g, dt = d.observer_d.K, d.lqi2, d.dt
    n = 7 + 6 + 2
    XP, XO, IZ, IW = slice(0, 7), slice(7, 13), 13, 14     # state blocks
    REF, VH, W_TAU, W_H, V_V, V_T = range(6)               # inputs
    # every signal s = Sx X + Su U; the Kalman update x_post = x_prior + K (y - Cm x_prior)
    Px, Pu = np.zeros((6, n)), np.zeros((6, 6))
    Px[:, XP] = K @ C[[1, 0]]                              # y = [w_m, tau_s] of the plant + noise
    Px[:, XO] = np.eye(6) - K @ d.Cm
    Pu[:, [V_V, V_T]] = K
    # u = -F'_ix x_post - F'_iz z - F_iz w                  eq. (13)
    Ux, Uu = -g.Kx @ Px, -g.Kx @ Pu
    Ux[0, IZ] -= g.Kz[0, 0]
    Ux[0, IW] -= g.Kzz[0, 0]
    # y_b_hat = Cb x_post - d_eh v_h                        eq. (6)
    Yx, Yu = d.Cb @ Px, d.Cb @ Pu
    Yu[0, VH] -= d.d_eh
    Phi, Gam = np.zeros((n, n)), np.zeros((n, 6))
    # plant: x' = Ad x + Bd[:, 0] (u + w_tau) + Bd[:, 1] (v_h + w_h)
    Phi[XP, XP] = Ad
    Phi[XP] += np.outer(Bd[:, 0], Ux[0])
    Gam[XP] += np.outer(Bd[:, 0], Uu[0])
    Gam[XP, W_TAU] += Bd[:, 0]
    Gam[XP, VH] += Bd[:, 1]
    Gam[XP, W_H] += Bd[:, 1]
    # observer: x_prior' = F x_post + Gd[:, 0] u + Gd[:, 1] v_h
    Phi[XO] = d.F @ Px + np.outer(d.Gd[:, 0], Ux[0])
    Gam[XO] = d.F @ Pu + np.outer(d.Gd[:, 0], Uu[0])
    Gam[XO, VH] += d.Gd[:, 1]
    # integrators: z' = z + dt (tau_ref - y_b_hat), w' = w + dt z      eqs. (10), (12)
    Phi[IZ] = -dt * Yx[0]
    Phi[IZ, IZ] += 1.0
    Gam[IZ] = -dt * Yu[0]
    Gam[IZ, REF] += dt
    Phi[IW, IZ], Phi[IW, IW] = dt, 1.0
    Cout, Dout = np.zeros((6, n)), np.zeros((6, 6))
    Cout[0], Dout[0] = Ux[0], Uu[0]
    Cout[1], Dout[1] = Yx[0], Yu[0]
    Cout[2], Dout[2] = Px[1], Pu[1]
    Cout[3, XP] = C[2]                                     # true y_b, with its -d_eh theta_h_dot term
    Dout[3, VH] = Dout[3, W_H] = D[2, 1]
    Cout[4, XP], Cout[5, XP] = C[1], C[0]
    return Phi, Gam, Cout, Dout


def monolithic(design: ExoDesign, t, noise, *, w_h: float, tau_ref: float, t_ref: float) -> dict:
    """The loop as one linear discrete-time system (plant: eq. (3) of [1]_ discretised
    exactly with ZOH), simulated with ``scipy.signal.dlsim``.

    Parameters
    ----------
    design : ExoDesign
    t : ndarray, shape (n + 1,), s
        Sample times ``k dt``.
    noise : ndarray, shape (n + 1, 4)
    w_h, tau_ref, t_ref : float
        As :func:`cosimulate`.

    Returns
    -------
    dict str -> ndarray, shape (n + 1,)
        ``tau_m`` (u), ``y_b_hat``, ``w_m_hat``, ``y_b``, ``w_m``, ``tau_s`` (true plant outputs).
    """
    from scipy.signal import dlsim

    t = np.asarray(t, dtype=float)
    ref = np.where(t >= t_ref - 1e-12 * max(1.0, t_ref), tau_ref, 0.0)
    U = np.column_stack([ref, np.full_like(t, w_h), np.asarray(noise, dtype=float)])
    Phi, Gam, Cout, Dout = _closed_loop_matrices(design)
    _, y, _ = dlsim((Phi, Gam, Cout, Dout, design.dt), U, t=t)
    return dict(zip(("tau_m", "y_b_hat", "w_m_hat", "y_b", "w_m", "tau_s"), y.T))
