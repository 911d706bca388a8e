"""A stiff model over many sample intervals: the linearly implicit Rosenbrock W-method ROS34PW2.

Classic RK4 (:mod:`bondgraph.numerics.evaluate_samples`) must take sub-steps shorter than
about :math:`0.5/|\\lambda_{max}|`.  A model with a fast mode it does not need to resolve -- a
smoothed Coulomb friction near zero speed (slope :math:`F_c/v_\\varepsilon`), a damper across a
stiff gear -- would then need thousands of sub-steps per sample.  This module integrates such a
model with ROS34PW2 (Rang and Angermann 2005, BIT Numer. Math. 45, 761-787, method "ROS34PW2"):
four stages, third order, L-stable, :math:`\\gamma = 0.43586652150845900`.  With
:math:`W = I - \\gamma h J` and the stage increments :math:`u_i = \\sum_{j \\le i} \\Gamma_{ij} k_j`
(the usual change of variables, Hairer and Wanner, Solving ODEs II, section IV.7):

.. math::

    W u_i = \\gamma h f\\Big(x_n + \\sum_{j<i} a_{ij} u_j\\Big) + \\sum_{j<i} c_{ij} u_j, \\qquad
    x_{n+1} = x_n + \\sum_i m_i u_i,

    a = \\alpha \\Gamma^{-1}, \\quad c = -\\gamma\\,L(\\Gamma^{-1}), \\quad m = b^T \\Gamma^{-1}

from the paper's tables :math:`\\alpha, \\Gamma, b` (:data:`ALPHA`, :data:`GAMMA_TABLE`, :data:`B`),
:math:`L` the strictly lower triangle.
It keeps order 3 with any :math:`W` (a W-method), so :math:`J = \\partial f/\\partial x` is
evaluated once per sample interval (or per piece of it, below), at its start, and :math:`W^{-1}`
serves all of its sub-steps.  Inputs are held over each interval (zero-order hold), as in the RK4 path.  (Until
2026-11 this was the second-order ROS2 of Verwer et al. 1999: see "Sub-steps" for why it went.)

Sub-steps: each interval takes ``m`` equal sub-steps of length :math:`h`.  A followed mode
:math:`\\lambda` of :math:`J` there takes, per step, an error of about
:data:`ERROR_CONSTANT` :math:`|h\\lambda|^4` of itself (the stability function's, measured in
``tests/test_numerics_stiff.py``), and a mode keeps its errors for its memory
:math:`\\min(1/|\\mathrm{Re}\\,\\lambda|, T)`, :math:`T` the record's span.  A lightly damped
oscillation so sums its phase errors over hundreds of periods: the pam's frictionless seesaw
(150 rad/s, :math:`|\\mathrm{Re}\\,\\lambda| \\approx 0.1` 1/s) took ROS2's rule, :math:`h|\\lambda|
\\le 0.1`, to 74 % of the joint torque's span off RK4 over 10 s.  So each step keeps the error
a mode sums over its memory under :data:`TOLERANCE`:

.. math::

    C\\,|h\\lambda|^3\\,\\max\\big(1, |\\lambda| \\min(1/|\\mathrm{Re}\\,\\lambda|, T)\\big) \\le \\mathrm{tol}.

The modes followed are those that grow (:math:`\\mathrm{Re}\\,\\lambda > 0`: L-stability would damp
them, and a diverging model must diverge) or that a sampled recording can show: one that turns
(:math:`|\\mathrm{Im}\\,\\lambda| \\ge \\tfrac12 |\\mathrm{Re}\\,\\lambda|`) below the Nyquist
frequency of the samples (:math:`|\\lambda| \\le \\pi/\\Delta t`), or that decays slowly enough to
show in the next sample (:math:`|\\lambda| \\Delta t \\le` :data:`VISIBLE`: down to
:math:`e^{-5}`, under 1 %, within it).  Other modes are not followed: a mode that decays faster
(a friction's slope at rest, a stiff damper) decays within the step, and a mode
above the Nyquist frequency (a stiff gear's kHz ringing in a 200 Hz recording) is damped by the
L-stability to its quasi-static response, all a recording at these samples can be compared
with.

That rule is linear: it reads the modes at the interval's start.  A sharp friction changes them
within an interval (sticking: a real mode at :math:`-F_c/(v_\\varepsilon J)`; sliding: none), where
the frozen :math:`J` is far from the true one.  So each interval is also checked with the
paper's embedded second-order solution (:data:`B_HAT`): where a sub-step's local error estimate
exceeds :data:`RTOL` of a state's largest magnitude so far (all rows, from the start of the
record; a state still at 0 is checked against where the piece took it), the piece is taken again
as two halves, each from the Jacobian at its own start and at half the step, down to
:data:`MIN_PIECE` of the interval (at most :data:`MAX_PIECES` pieces), far below the linear rule's
shortest sub-step (``dt /`` :data:`MAX_SUBSTEPS`): a Stribeck peak's falling slope on a nearly
massless part is a mode growing at 1e7 1/s while the speed crosses it, which no fixed grid
follows.  A shortest piece still above tolerance is kept (a sign sharper than it), unless a
state runs off to infinity in it (:func:`_check_blow_up`).  The
next piece starts from the step the last estimate asks for (third order in :math:`h`), not
longer than the linear rule's.  A Coulomb friction at the pam's seesaw sliding and sticking
(0.1 N m over 4 mrad/s) ran 8 % of tau's span off scipy's Radau on the linear rule alone, and
1e-5 with the check (at most 18 sub-steps per 1 ms sample; doubling the sub-steps without a new
Jacobian needed 80).  Every row of a batch shares the steps.
"""
from __future__ import annotations

import numpy as np

from ..errors import SimulationError

__all__ = ["rosenbrock_samples", "MAX_SUBSTEPS", "MIN_PIECE", "MAX_PIECES", "BLOW_UP", "TOLERANCE",
           "ERROR_CONSTANT", "RTOL"]

#: ROS34PW2's tables alpha_ij, gamma_ij, b_i as the paper gives them (checked in tests/test_numerics_stiff.py:
#: order 3 with an exact, a frozen and a wrong J; L-stable)
GAMMA = 0.43586652150845900
ALPHA = np.array([[0.0, 0.0, 0.0, 0.0],
                  [0.87173304301691801, 0.0, 0.0, 0.0],
                  [0.84457060015369423, -0.11299064236484185, 0.0, 0.0],
                  [0.0, 0.0, 1.0, 0.0]])
GAMMA_TABLE = np.array([[GAMMA, 0.0, 0.0, 0.0],
                        [-0.87173304301691801, GAMMA, 0.0, 0.0],
                        [-0.90338057013044082, 0.054180672388095326, GAMMA, 0.0],
                        [0.24212380706095346, -1.2232505839045147, 0.54526025533510214, GAMMA]])
B = np.array([0.24212380706095346, -1.2232505839045147, 1.5452602553351020, GAMMA])
#: the embedded second-order solution's weights (the paper's b-hat)
B_HAT = np.array([0.37810903145819369, -0.096042292212423178, 0.5, 0.21793326075422950])
_GAMMA_INV = np.linalg.inv(GAMMA_TABLE)
#: the stages' coefficients in the increments u (module docstring): a_ij, c_ij (i > j) and m_i
STAGE_A = ALPHA @ _GAMMA_INV
STAGE_C = -GAMMA * np.tril(_GAMMA_INV, -1)
STAGE_M = B @ _GAMMA_INV
#: the local error estimate's weights in u: x_{n+1} minus the embedded solution
STAGE_E = (B - B_HAT) @ _GAMMA_INV
#: |R(z) - e^z| / |z|^4 of ROS34PW2's stability function R for small |z| (0.0255-0.0259 from the
#: imaginary to the negative real axis): the error per step of a mode, as a share of it
ERROR_CONSTANT = 0.026
#: the error a followed mode may sum over its memory, as a share of it (module docstring)
TOLERANCE = 0.003
#: the local error estimate a sub-step may leave, as a share of each state's largest magnitude so far
RTOL = 1e-4
#: most sub-steps the linear rule gives one sample interval
MAX_SUBSTEPS = 4096
#: the shortest piece the error check halves an interval into, as a share of it, and the most
#: pieces one interval is cut into (beyond either, a piece is kept at its error).  Seed 4141 case
#: 018's truth runs as at 2048 with 256 and not at 64; at 2048 a Stribeck candidate on the
#: exoskeleton's sensor ring took over ten minutes of fitting (each piece costs about 0.1 ms in Python)
MIN_PIECE, MAX_PIECES = 2.0 ** -20, 256
#: |lambda| dt up to which a decaying mode is followed: it leaves e^-5 of itself at the next sample.
#: One step over a mode at |lambda| dt = 1.65 leaves 0.34 of it, not 0.19: a viscous damper across
#: the exoskeleton's torque sensor (91 N m s/rad) made a mode at -330 1/s in a 200 Hz recording,
#: and at the truth's value the training error was 30 times Radau's (seed 7171, case 026)
VISIBLE = 5.0


def _sub_step_count(J, dt: float, span: float) -> int:
    """Sub-steps of an interval of `dt` s in a record of `span` s from the Jacobians `J`
    (n_batch, n, n): the error each followed mode sums over its memory stays under TOLERANCE."""
    lam = np.linalg.eigvals(J).ravel()
    turning = (np.abs(lam.imag) >= 0.5 * np.abs(lam.real)) & (np.abs(lam) <= np.pi / dt)
    lam = lam[turning | (lam.real > 0) | (np.abs(lam) * dt <= VISIBLE)]
    if not lam.size:
        return 1
    with np.errstate(divide="ignore"):
        memory = np.minimum(1.0 / np.abs(lam.real), max(span, dt))
    reach = np.cbrt(TOLERANCE / (ERROR_CONSTANT * np.maximum(1.0, np.abs(lam) * memory)))   # |h lambda|
    return int(min(max(np.ceil(float(np.max(dt * np.abs(lam) / reach)) - 1e-9), 1), MAX_SUBSTEPS))


def rosenbrock_samples(model, t, U, x, d, p, *, use_c: bool = True):
    """Integrate a batch over the sample intervals of `t` with ROS34PW2 (module docstring).

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
    most, span = 1, float(t[-1] - t[0])
    scale, h_hint = np.zeros(x.shape[1]), np.inf
    attempt = _attempt(model, n, d, p, p_rows, use_c)
    U = np.ascontiguousarray(U, dtype=float)
    for k in range(t.size - 1):
        u = np.broadcast_to(U[k], (n, U.shape[1]))
        dt = float(t[k + 1] - t[k])
        scale = np.maximum(scale, np.max(np.abs(x), axis=0))
        tol = RTOL * np.where(scale > 0, scale, np.inf)        # a state still at 0 has no scale yet
        pieces, taken, cut = [(float(t[k]), dt)], 0, 1
        while pieces:
            t0, length = pieces.pop()
            J = _jacobian(model, x, u, t0, p, d)
            h = min(dt / _sub_step_count(J, dt, span), h_hint)
            m = int(min(np.ceil(length / h - 1e-9), np.ceil(length / dt * MAX_SUBSTEPS - 1e-9)))
            h = length / m
            x_new, err = attempt(x, U[k], u, t0, h, m, J, tol)
            if np.isinf(tol).any():
                # a state leaving 0 is checked against where the piece took it (a fall from an
                # unstable rest, unchecked, settled 8 % of the way to its stable rest)
                reach = np.maximum(scale, np.max(np.abs(x_new), axis=0))
                if np.any(np.isinf(tol) & (reach > 0)):
                    tol = RTOL * np.where(reach > 0, reach, np.inf)
                    x_new, err = attempt(x, U[k], u, t0, h, m, J, tol)
            if not err <= 1.0 and length <= MIN_PIECE * dt:
                _check_blow_up(model, np.maximum(scale, np.max(np.abs(x), axis=0)), x_new, t0)
            elif not err <= 1.0 and cut < MAX_PIECES:    # NaN too
                # taken again in halves, each from the Jacobian at its start and at half the step
                pieces += [(t0 + 0.5 * length, 0.5 * length), (t0, 0.5 * length)]
                h_hint, cut = 0.5 * h, cut + 1
                continue
            x, taken = x_new, taken + m
            if not np.isfinite(x).all():
                break
            h_hint = h / (1.25 * np.cbrt(max(err, 1e-3))) if np.isfinite(err) else h
        if not np.isfinite(x).all():
            bad = [nm for nm, v in zip(model.state_names, x.T) if not np.isfinite(v).all()]
            raise SimulationError(f"model {model.equations.name!r}: non-finite state(s) {', '.join(bad)} "
                                  f"at t = {t[k + 1]:.6g} s (linearly implicit ROS34PW2)", time=float(t[k + 1]))
        X[k + 1] = x
        most = max(most, taken)
    return X, D, most


#: a state this many times its largest magnitude so far after a shortest piece still above tolerance
#: runs off to infinity within the interval
BLOW_UP = 10.0


def _check_blow_up(model, scale, x_new, t0):
    """A shortest piece (:data:`MIN_PIECE` of its interval) still above tolerance is kept, unless it
    took a state beyond :data:`BLOW_UP` times its largest magnitude so far (`scale`, the piece's
    start included) or out of the finite numbers (a finite-time blow-up): then a SimulationError
    names those states.  Otherwise the model has a sign sharper than the shortest piece: the
    exoskeleton's sensor ring, nearly massless, sweeps a gear friction's 0.26 mrad/s sign in about
    1e-11 s; its 5 ns pieces kept, a run at seed 4141 case 018's truth trains at 3.8e-4 (Radau:
    2.3e-4; before this check halved below 1.2 us pieces, it diverged)."""
    with np.errstate(all="ignore"):
        peak = np.max(np.abs(x_new), axis=0)
    bad = [nm for nm, a, s in zip(model.state_names, peak, scale) if (s > 0 and a > BLOW_UP * s) or not np.isfinite(a)]
    if bad:
        raise SimulationError(f"model {model.equations.name!r}: non-finite state(s) {', '.join(bad)} ahead: they run "
                              f"past {BLOW_UP:g} times their largest magnitude within {MIN_PIECE:.2g} of a sample "
                              f"interval at t = {t0:.6g} s (linearly implicit ROS34PW2)", time=t0)


def _jacobian(model, x, u, t, p, d):
    """The batch's Jacobians of the state derivatives at `x`; a SimulationError where not finite."""
    with np.errstate(all="ignore"):        # a run leaving the finite numbers is named
        J = model.jac_x(x, u, t=t, p=p, d=d)
    if not np.isfinite(J).all():
        raise SimulationError(f"model {model.equations.name!r}: non-finite Jacobian of the state "
                              f"derivatives at t = {t:.6g} s (linearly implicit ROS34PW2)", time=t)
    return J


def _attempt(model, n, d, p, p_rows, use_c):
    """A function ``(x, u_row, u, t0, h, m, J, tol) -> (x_new, err)``: `m` sub-steps of `h` from
    `x` (unchanged) with ``W = I - gamma h J``, and the largest local error estimate against
    `tol` (per state) over them, in C where the model allows, else in Python."""
    sub_steps = _c_sub_steps(model, n, d, p_rows) if use_c else None
    eye = np.eye(len(model.state_names))

    def attempt(x, u_row, u, t0, h, m, J, tol):
        with np.errstate(all="ignore"):    # a run leaving the finite numbers is named by the caller
            Winv = np.linalg.inv(eye - (GAMMA * h) * J)
            if sub_steps is not None:
                x_new = x.copy()
                return x_new, sub_steps(x_new, u_row, t0, h, m, Winv, tol)
            x_new, err = x, 0.0
            for i in range(m):
                x_new, e = _python_sub_step(model, x_new, u, t0 + i * h, p, d, h, Winv)
                e = float(np.max(np.abs(e) / tol))
                err = e if np.isnan(e) else max(err, e)
            return x_new, err
    return attempt


def _python_sub_step(model, x, u, t, p, d, h, Winv):
    """One ROS34PW2 sub-step of length `h` on the batch `x` (module docstring), its sums in the C
    driver's order; every stage sees the time `t` at the sub-step's start (inputs are held)."""
    stages = []
    for i in range(B.size):
        xs = x.copy()
        for j in range(i):
            if STAGE_A[i, j] != 0.0:
                xs += STAGE_A[i, j] * stages[j]
        rhs = model.f(xs, u, t=t, p=p, d=d) * (GAMMA * h)
        for j in range(i):
            if STAGE_C[i, j] != 0.0:
                rhs += STAGE_C[i, j] * stages[j]
        stages.append(np.einsum("nij,nj->ni", Winv, rhs))
    x, error = x.copy(), np.zeros_like(x)
    for m_i, e_i, u_i in zip(STAGE_M, STAGE_E, stages):
        x += m_i * u_i
        error += e_i * u_i
    return x, error


def _c_sub_steps(model, n, d, p_rows):
    """A function ``(x, u_row, t0, h, m, Winv, tol)`` taking `m` sub-steps on `x` in place in C and
    returning the largest local error estimate against `tol` (per state), or
    None where the model needs the Python loop (:func:`~bondgraph.numerics.evaluate_stiff_c.c_derivative`)."""
    from .evaluate_stiff_c import c_derivative, steps_driver
    fn = c_derivative(model)
    if fn is None:
        return None
    driver, nx = steps_driver(), len(model.state_names)
    d = np.ascontiguousarray(np.broadcast_to(np.asarray(d, dtype=float), (n, np.shape(d)[-1])))
    z, work = np.zeros(1), np.empty((2 + B.size) * n * nx)
    a, c, mw, me = (np.ascontiguousarray(v, dtype=float) for v in (STAGE_A, STAGE_C, STAGE_M, STAGE_E))
    sp = 0 if p_rows.shape[0] == 1 and n != 1 else p_rows.shape[1]

    def steps(x, u_row, t0, h, m, Winv, tol):
        u_row, Winv = np.ascontiguousarray(u_row, dtype=float), np.ascontiguousarray(Winv)
        tol = np.ascontiguousarray(tol, dtype=float)
        return driver(fn, n, nx, t0, h, m, B.size, a.ctypes.data, c.ctypes.data, mw.ctypes.data, me.ctypes.data,
                      tol.ctypes.data, GAMMA, x.ctypes.data, u_row.ctypes.data, z.ctypes.data, d.ctypes.data,
                      d.shape[1], p_rows.ctypes.data, sp, Winv.ctypes.data, work.ctypes.data)
    return steps
