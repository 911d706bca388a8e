"""Numpy backend of :func:`bondgraph.numerics.evaluate.compile_model`: lambdified kernels.

:class:`NumpyKernels` implements the kernel interface of :mod:`bondgraph.numerics.evaluate`
with :func:`sympy.lambdify` (``cse=True``) vectorised over the batch.  The
algebraic loops are solved by Newton's method vectorised over the rows still
iterating, with :func:`numpy.linalg.solve` on stacked Jacobians, and fixed-step
integration runs RK4 sub-steps in numpy: the same iterations, tolerances and
status codes as the C ``bc_solve`` and ``bc_rk4``
(:mod:`bondgraph.numerics.codegen_c_templates`), so both backends agree to rounding.
"""
from __future__ import annotations

import numpy as np
import sympy as sp

from .codegen_c import PARTS, jacobian_entries, prepare_expression
from .codegen_c_templates import NEWTON_ATOL, NEWTON_FLOOR_RTOL, NEWTON_FLOOR_RUN, NEWTON_MAX_ITER, NEWTON_RTOL

__all__ = ["NumpyKernels", "select_rows"]


class NumpyKernels:
    """Kernels of `eqs` as lambdified numpy functions (the interface of :mod:`bondgraph.numerics.evaluate`).

    The main kernels (``f``, ``h``, ``held_update``, ``residuals``, ``jac_rz``)
    are built at construction, the other Jacobians on first use.

    Parameters
    ----------
    eqs : StateEquations
    """

    backend = "numpy"

    def __init__(self, eqs):
        self._eqs = eqs
        # Own renaming to plain identifiers (lambdify's dummify is quadratic in the
        # number of arguments): X_i, U_i, Z_i, D_i, P_i, T_, STEP_.
        self._rename = {eqs.t: sp.Symbol("T_"), eqs.step: sp.Symbol("STEP_")}
        self._args = [self._rename[eqs.t]]
        for prefix, syms in (("X", eqs.states), ("U", eqs.inputs), ("Z", eqs.algebraic),
                             ("D", eqs.held), ("P", eqs.params)):
            plain = [sp.Symbol(f"{prefix}_{i}") for i in range(len(syms))]
            self._rename.update(zip(syms, plain))
            self._args.append(plain)
        self._args.append(self._rename[eqs.step])
        nx, nz = len(eqs.states), len(eqs.algebraic)
        self._specs = {
            "f": lambda: (list(enumerate(eqs.f)), nx),
            "h": lambda: (list(enumerate(eqs.h)), len(eqs.h)),
            "held_update": lambda: (list(enumerate(eqs.held_update)), len(eqs.held)),
            "residuals": lambda: (list(enumerate(eqs.residuals)), nz),
            "jac_rz": lambda: (jacobian_entries(eqs.residuals, eqs.algebraic), nz * nz),
            "jac_fx": lambda: (jacobian_entries(eqs.f, eqs.states), nx * nx),
            "jac_fz": lambda: (jacobian_entries(eqs.f, eqs.algebraic), nx * nz),
            "jac_rx": lambda: (jacobian_entries(eqs.residuals, eqs.states), nz * nx),
        }
        self._fns = {}
        for name in PARTS["main"]:
            self._build(name)

    def _build(self, name):
        targets, size = self._specs[name]()
        index = [k for k, _ in targets]
        exprs = [prepare_expression(e).xreplace(self._rename) for _, e in targets]
        fn = sp.lambdify(self._args, exprs, modules="numpy", cse=True, dummify=False)
        self._fns[name] = (fn, index, size)
        return self._fns[name]

    def call(self, name, t, x, u, z, d, p, step, out):
        fn, index, size = self._fns.get(name) or self._build(name)
        flat = out.reshape(out.shape[0], size)
        if len(index) < size:
            flat[...] = 0.0
        with np.errstate(all="ignore"):
            values = fn(t, x.T, u.T, z.T, d.T, p.T, step)
            for k, v in zip(index, values):
                flat[:, k] = v

    def solve(self, t, x, u, z, d, p):
        return _newton_numpy(self, t, x, u, z, d, p)

    def rk4(self, t0, h, m, x, u, z, zinit, d, p, every=1):
        return _rk4_python(self, t0, h, m, x, u, z, zinit, d, p, every)


def _rk4_python(kern, t0, h, m, x, u, z, zinit, d, p, every=1):
    """The C ``bc_rk4_every`` in numpy: m RK4 sub-steps, x, z, d updated in place, the held
    values at every `every`-th sub-step start (over ``every h``).
    Stops at the first Newton failure and returns the status of every row."""
    n, nx = x.shape
    has_z, has_d = z.shape[1] > 0, d.shape[1] > 0
    k = np.empty((4, n, nx))

    def solve(tt, xx):
        status = kern.solve(tt, xx, u, z, d, p)
        if status.any():   # retry the failed rows from zinit
            z[status != 0] = zinit
            status = kern.solve(tt, xx, u, z, d, p)
        return status

    def stage(i, tt, xx):
        status = solve(tt, xx) if has_z else None
        if status is not None and status.any():
            return status
        kern.call("f", tt, xx, u, z, d, p, 0.0, k[i])
        return None

    for j in range(m):
        t = np.array([t0 + j * h])
        if has_d and j % every == 0:
            status = solve(t, x) if has_z else None
            if status is not None and status.any():
                return status
            dn = np.empty_like(d)
            kern.call("held_update", t, x, u, z, d, p, h * every, dn)
            d[...] = dn
        for i, (c, a) in enumerate(((0.0, 0.0), (0.5, 0.5), (0.5, 0.5), (1.0, 1.0))):
            xx = x if i == 0 else np.ascontiguousarray(x + (a * h) * k[i - 1])
            status = stage(i, t + c * h, xx)
            if status is not None:
                return status
        x += (h / 6.0) * (k[0] + 2.0 * k[1] + 2.0 * k[2] + k[3])
    return np.zeros(n, dtype=np.intc)


def select_rows(a: np.ndarray, idx, n: int) -> np.ndarray:
    """Rows `idx` of a broadcastable batch array, or `a` itself when it is one
    row shared by a batch of n > 1 rows."""
    return a if a.shape[0] == 1 and n != 1 else a[idx]


def _newton_numpy(kern, t, x, u, z, d, p):
    """Newton iteration vectorised over the batch rows still iterating.

    The same iteration as the C ``bc_newton_row``: :math:`J \\Delta z = -r`
    with :math:`J = \\partial r/\\partial z`; full step unless it increases
    :math:`|r|^2`, then halved at most 10 times; converged when
    :math:`|\\Delta z_k| \\le` ``NEWTON_RTOL`` :math:`|z_k| +` ``NEWTON_ATOL``, or at the
    residual's rounding floor: :math:`|\\Delta z_k| \\le` ``NEWTON_FLOOR_RTOL``
    :math:`|z_k| +` ``NEWTON_ATOL`` and no trial step lowers :math:`|r|^2` (z kept), or
    after ``NEWTON_FLOOR_RUN`` such steps in a row.
    """
    n, nz = z.shape
    status = np.zeros(n, dtype=np.intc)
    if nz == 0 or n == 0:
        return status

    def resid(idx, zz):
        out = np.empty((idx.size, nz))
        kern.call("residuals", select_rows(t, idx, n), np.ascontiguousarray(x[idx]),
                  select_rows(u, idx, n), np.ascontiguousarray(zz), select_rows(d, idx, n),
                  select_rows(p, idx, n), 0.0, out)
        return out

    active = np.arange(n)
    r = resid(active, z)
    nr = np.sum(r * r, axis=1)
    status[~np.isfinite(nr)] = 3
    keep = np.isfinite(nr) & (nr != 0.0)
    active, r, nr = active[keep], r[keep], nr[keep]
    run = np.zeros(active.size, dtype=int)     # tiny steps in a row, per row
    for _ in range(NEWTON_MAX_ITER):
        if active.size == 0:
            break
        J = np.empty((active.size, nz, nz))
        kern.call("jac_rz", select_rows(t, active, n), np.ascontiguousarray(x[active]),
                  select_rows(u, active, n), np.ascontiguousarray(z[active]),
                  select_rows(d, active, n), select_rows(p, active, n), 0.0, J)
        dz, singular = _solve_stacked(J, -r)
        za = z[active]
        small = np.all(np.abs(dz) <= NEWTON_RTOL * np.abs(za) + NEWTON_ATOL, axis=1)
        tiny = np.all(np.abs(dz) <= NEWTON_FLOOR_RTOL * np.abs(za) + NEWTON_ATOL, axis=1)
        # backtracking on |r|^2, rows independently
        lam = np.ones(active.size)
        pending = ~singular
        zt, rt, nrt = za.copy(), r.copy(), nr.copy()
        for _ls in range(11):
            if not pending.any():
                break
            sel = np.flatnonzero(pending)
            trial = za[sel] + lam[sel, None] * dz[sel]
            rr = resid(active[sel], trial)
            nn = np.sum(rr * rr, axis=1)
            zt[sel], rt[sel], nrt[sel] = trial, rr, nn
            ok = np.isfinite(nn) & ((nn <= nr[sel]) | small[sel])
            pending[sel[ok]] = False
            lam[sel[~ok]] *= 0.5
        status[active[singular]] = 2
        floor = ~singular & pending & tiny          # no trial lowered |r|: its rounding floor, z kept
        bad = ~singular & ~floor & ~np.isfinite(nrt)
        status[active[bad]] = 3
        go = ~singular & ~bad & ~floor
        z[active[go]] = zt[go]
        run = np.where(tiny, run + 1, 0)
        done = go & ((small & (lam == 1.0)) | (nrt == 0.0) | (run >= NEWTON_FLOOR_RUN))
        cont = go & ~done
        active, r, nr, run = active[cont], rt[cont], nrt[cont], run[cont]
    status[active] = 1
    return status


def _solve_stacked(J, b):
    """Solve ``J[i] y[i] = b[i]``; rows with a singular or non-finite J are flagged."""
    finite = np.isfinite(J).all(axis=(1, 2)) & np.isfinite(b).all(axis=1)
    y = np.zeros_like(b)
    singular = ~finite
    idx = np.flatnonzero(finite)
    try:
        y[idx] = np.linalg.solve(J[idx], b[idx, :, None])[..., 0]
    except np.linalg.LinAlgError:
        for i in idx:
            try:
                y[i] = np.linalg.solve(J[i], b[i])
            except np.linalg.LinAlgError:
                singular[i] = True
    singular |= ~np.isfinite(y).all(axis=1)
    return y, singular
