"""A stiff model over many sample intervals: the linearly implicit ROS2 method.

Classic RK4 (:mod:`bondgraph.numerics.evaluate_samples`) must take sub-steps shorter than
about :math:`0.5/|\\lambda_{max}|`.  A model with a fast mode it does not need to resolve -- a
smoothed Coulomb friction near zero speed (slope :math:`F_c/v_\\varepsilon`), a damper across a
stiff gear -- would then need thousands of sub-steps per sample.  This module integrates such a
model with the two-stage Rosenbrock method ROS2 (Verwer, Spee, Blom and Hundsdorfer 1999,
SIAM J. Sci. Comput. 20(4), eq. 2.5), L-stable, with :math:`\\gamma = 1 + 1/\\sqrt 2` and
:math:`W = I - \\gamma h J`:

.. math::

    W k_1 = f(x_n), \\qquad W k_2 = f(x_n + h k_1) - 2 k_1, \\qquad
    x_{n+1} = x_n + \\tfrac32 h k_1 + \\tfrac12 h k_2 .

ROS2 keeps order 2 with any :math:`W` (it is a W-method), so :math:`J = \\partial f/\\partial x`
is evaluated once per sample interval, at its start, and :math:`W^{-1}` serves all of its
sub-steps.  Inputs are held over each interval (zero-order hold), as in the RK4 path.

Sub-steps: each interval takes ``m`` equal sub-steps of :math:`h \\le 0.1/|\\lambda|`
(:data:`ACCURACY`; RK4, of fourth order, takes 0.5) for every eigenvalue :math:`\\lambda` of
:math:`J` there that grows (:math:`\\mathrm{Re}\\,\\lambda > 0`: L-stability would damp it,
and a diverging model must diverge) or that a sampled recording can show: one that turns
(:math:`|\\mathrm{Im}\\,\\lambda| \\ge \\tfrac12 |\\mathrm{Re}\\,\\lambda|`) below the Nyquist
frequency of the samples (:math:`|\\lambda| \\le \\pi/\\Delta t`), or that decays slowly enough to
show in the next sample (:math:`|\\lambda| \\Delta t \\le` :data:`VISIBLE`: down to
:math:`e^{-5}`, under 1 %, within it).  Other modes are not followed: a mode that decays faster
(a friction's slope at rest, a stiff damper) decays within the step, and a mode
above the Nyquist frequency (a stiff gear's kHz ringing in a 200 Hz recording) is damped by the
L-stability to its quasi-static response, all a recording at these samples can be compared
with.  Every row of a batch shares the steps.
"""
from __future__ import annotations

import numpy as np

from ..errors import SimulationError

__all__ = ["ros2_samples", "MAX_SUBSTEPS", "ACCURACY"]

#: ROS2's gamma: 1 + 1/sqrt(2) makes it L-stable
GAMMA = 1.0 + 1.0 / np.sqrt(2.0)
#: h |lambda| per sub-step for the modes a step follows (second order: a fifth of RK4's 0.5)
ACCURACY = 0.1
#: most sub-steps of one sample interval
MAX_SUBSTEPS = 4096
#: |lambda| dt up to which a decaying mode is followed: it leaves e^-5 of itself at the next sample.
#: One step over a mode at |lambda| dt = 1.65 leaves 0.34 of it, not 0.19: a viscous damper across
#: the exoskeleton's torque sensor (91 N m s/rad) made a mode at -330 1/s in a 200 Hz recording,
#: and at the truth's value the training error was 30 times Radau's (seed 7171, case 026)
VISIBLE = 5.0


def _sub_step_count(J, dt: float) -> int:
    """Sub-steps of an interval of `dt` s from the Jacobians `J` (n_batch, n, n)."""
    lam = np.linalg.eigvals(J).ravel()
    turning = (np.abs(lam.imag) >= 0.5 * np.abs(lam.real)) & (np.abs(lam) <= np.pi / dt)
    followed = lam[turning | (lam.real > 0) | (np.abs(lam) * dt <= VISIBLE)]
    fastest = float(np.max(np.abs(followed))) if followed.size else 0.0
    return int(min(max(np.ceil(dt * fastest / ACCURACY - 1e-9), 1), MAX_SUBSTEPS))


def ros2_samples(model, t, U, x, d, p, *, use_c: bool = True):
    """Integrate a batch over the sample intervals of `t` with ROS2 (module docstring).

    Parameters
    ----------
    model : bondgraph.numerics.evaluate.CompiledModel
        A smooth model (no held variables are updated: `d` is passed through as is).
    t : ndarray, shape (n_t,)
        Sample times, s.
    U : ndarray, shape (n_t, n_inputs)
        Inputs, held over ``[t_k, t_{k+1})`` at ``U[k]``.
    x : ndarray, shape (n_batch, n_states)
        Initial states.
    d : ndarray, shape (n_batch, n_held)
        Held values (constant).
    p : ndarray, shape (1 or n_batch, n_params)
        Parameters.
    use_c : bool
        Take each interval's sub-steps in C (:mod:`bondgraph.numerics.evaluate_stiff_c`) where
        the model allows (C backend, no algebraic loops, a compiler found); False: the Python
        loop (the reference and the fallback).

    Returns
    -------
    X : ndarray, shape (n_t, n_batch, n_states)
    D : ndarray, shape (n_t, n_batch, n_held)
    most : int
        The most sub-steps any interval took.

    Raises
    ------
    SimulationError
        A non-finite state (named, with the time) or Jacobian.
    """
    x = np.array(x, dtype=float)
    n = x.shape[0]
    p_rows = np.ascontiguousarray(p, dtype=float).reshape(-1, np.shape(p)[-1])
    p = np.broadcast_to(p_rows, (n, p_rows.shape[1]))
    X = np.empty((t.size, *x.shape))
    D = np.broadcast_to(np.asarray(d, dtype=float), (t.size, *np.shape(d))).copy()
    X[0] = x
    eye, most = np.eye(x.shape[1]), 1
    sub_steps = _c_sub_steps(model, n, d, p_rows) if use_c else None
    U = np.ascontiguousarray(U, dtype=float)
    for k in range(t.size - 1):
        u = np.broadcast_to(U[k], (n, U.shape[1]))
        dt, tk = float(t[k + 1] - t[k]), float(t[k])
        with np.errstate(all="ignore"):        # a run leaving the finite numbers is named below
            J = model.jac_x(x, u, t=tk, p=p, d=d)
            if not np.isfinite(J).all():
                raise SimulationError(f"model {model.equations.name!r}: non-finite Jacobian of the state "
                                      f"derivatives at t = {tk:.6g} s (linearly implicit ROS2)", time=tk)
            m = _sub_step_count(J, dt)
            h = dt / m
            Winv = np.linalg.inv(eye - (GAMMA * h) * J)
            if sub_steps is not None:
                sub_steps(x, U[k], tk, h, m, Winv)
            else:
                for _ in range(m):
                    k1 = np.einsum("nij,nj->ni", Winv, model.f(x, u, t=tk, p=p, d=d))
                    k2 = np.einsum("nij,nj->ni", Winv, model.f(x + h * k1, u, t=tk, p=p, d=d) - 2.0 * k1)
                    x = x + 1.5 * h * k1 + 0.5 * h * k2
                    tk += h
        if not np.isfinite(x).all():
            bad = [nm for nm, v in zip(model.state_names, x.T) if not np.isfinite(v).all()]
            raise SimulationError(f"model {model.equations.name!r}: non-finite state(s) {', '.join(bad)} "
                                  f"at t = {t[k + 1]:.6g} s (linearly implicit ROS2)", time=float(t[k + 1]))
        X[k + 1] = x
        most = max(most, m)
    return X, D, most


def _c_sub_steps(model, n, d, p_rows):
    """A function ``(x, u_row, t0, h, m, Winv)`` taking `m` sub-steps on `x` in place in C, or
    None where the model needs the Python loop (:func:`~bondgraph.numerics.evaluate_stiff_c.c_derivative`)."""
    from .evaluate_stiff_c import c_derivative, steps_driver
    fn = c_derivative(model)
    if fn is None:
        return None
    driver, nx = steps_driver(), len(model.state_names)
    d = np.ascontiguousarray(np.broadcast_to(np.asarray(d, dtype=float), (n, np.shape(d)[-1])))
    z, work = np.zeros(1), np.empty(4 * n * nx)
    sp = 0 if p_rows.shape[0] == 1 and n != 1 else p_rows.shape[1]

    def steps(x, u_row, t0, h, m, Winv):
        u_row, Winv = np.ascontiguousarray(u_row, dtype=float), np.ascontiguousarray(Winv)
        driver(fn, n, nx, t0, h, m, x.ctypes.data, u_row.ctypes.data, z.ctypes.data, d.ctypes.data,
               d.shape[1], p_rows.ctypes.data, sp, Winv.ctypes.data, work.ctypes.data)
    return steps
