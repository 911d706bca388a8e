"""RK4 over many sample intervals in one call: :meth:`CompiledModel.rk4_samples`.

One compiled RK4 call per sample interval, inputs held over it.  On the C
backend the loop calls ``bc_rk4`` (its C contract is documented in
:mod:`bondgraph.numerics.codegen_c`) with the argument pointers computed once, which
takes the per-sample cost from about 13 us (``CompiledModel.rk4_step``
argument normalisation) to about 5 us on pam, and the C loop of
:mod:`bondgraph.numerics.evaluate_samples_c` (the same calls, when a compiler is found)
to about 2 us; other backends go through ``CompiledModel._rk4``.  All give identical
numbers (tested in ``tests/test_diagnosis_residuals.py``).  A batch of rows (parameter
sets) is integrated in the same calls.
"""
from __future__ import annotations

import numpy as np

from .evaluate_samples_c import run_samples, sample_driver

__all__ = ["rk4_samples"]


def _c_function(model):
    kernels = getattr(model, "_k", None)
    main = getattr(kernels, "_main", None)
    return getattr(main, "rk4", None) if model.backend == "c" else None


def rk4_samples(model, t, U, subs, x, d, p, *, use_driver: bool = True, every: int = 1):
    """Integrate a batch over the sample intervals of `t`.

    Parameters
    ----------
    model : bondgraph.numerics.evaluate.CompiledModel
    t : ndarray, shape (n_t,)
        Sample times, s.
    U : ndarray, shape (n_t, n_inputs)
        Inputs, held over ``[t_k, t_{k+1})`` at ``U[k]`` (zero-order hold).
    subs : ndarray of int, shape (n_t - 1,)
        RK4 sub-steps per interval.
    x : ndarray, shape (n_batch, n_states)
        Initial states (C-contiguous; overwritten with the final ones).
    d : ndarray, shape (n_batch, n_held)
        Initial held values (overwritten).
    p : ndarray, shape (1 or n_batch, n_params)
        Parameters.
    use_driver : bool
        On the C backend, loop over the samples in C
        (:mod:`bondgraph.numerics.evaluate_samples_c`) when a compiler is found; False: the
        Python loop (the same calls; kept as the reference and the fallback).
    every : int
        Held values are updated at every `every`-th sub-step start, over ``every`` sub-steps
        (a discrete law's interval with finer RK4 steps nested in it; ``bc_rk4_every``).

    Returns
    -------
    X : ndarray, shape (n_t, n_batch, n_states)
    D : ndarray, shape (n_t, n_batch, n_held)
        Held values in effect over the last sub-step before each sample.

    Raises
    ------
    SimulationError
        Newton's method failed on an algebraic loop (time and rows named).
    """
    n = x.shape[0]
    X = np.empty((t.size, *x.shape))
    D = np.empty((t.size, *d.shape))
    X[0], D[0] = x, d
    hs_arr = np.diff(t) / subs
    hs = hs_arr.tolist()
    ms = np.asarray(subs, dtype=int).tolist()
    ts = t.tolist()
    rk4 = _c_function(model)
    if rk4 is None:
        for k in range(t.size - 1):
            model._rk4(ts[k], hs[k], ms[k], x, U[k:k + 1], p, d, every)
            X[k + 1], D[k + 1] = x, d
        return X, D
    U = np.ascontiguousarray(U, dtype=float)
    p = np.ascontiguousarray(p, dtype=float)
    z = np.ascontiguousarray(np.tile(model.initial_guess, (n, 1)))
    zinit = np.ascontiguousarray(model.initial_guess, dtype=float)
    status = np.zeros(n, dtype=np.intc)
    xa, za, zia, da, pa, sa = (a.ctypes.data for a in (x, z, zinit, d, p, status))
    ua, row = U.ctypes.data, U.shape[1] * U.itemsize
    sp = 0 if p.shape[0] == 1 and n != 1 else p.shape[1]
    check = bool(model.algebraic_names)
    driver = sample_driver() if use_driver else None
    if driver is not None:
        # the same bc_rk4 calls from a C loop (bit for bit the loop below, without ~3 us of
        # Python per sample)
        args = (driver, rk4, np.ascontiguousarray(t, dtype=float), np.ascontiguousarray(hs_arr),
                np.ascontiguousarray(subs, dtype=np.intc), U)
        chunks = _row_chunks(n, t.size)
        if len(chunks) > 1 and _threaded(args, chunks, x, z, zinit, d, p, sp, check, X, D, every):
            return X, D
        k = run_samples(*args, x, z, zinit, d, p, sp, status, check, X, D, every)
        if k < 0:
            raise MemoryError("bc_rk4: out of memory")
        if k < t.size - 1:
            model._raise_newton(status, np.array([ts[k]]), x)
        return X, D
    for k in range(t.size - 1):
        # u stride 0: every batch row sees the recorded input row k
        if rk4(n, ts[k], hs[k], ms[k], every, xa, ua + k * row, 0, za, zia, da, pa, sp, sa) < 0:
            raise MemoryError("bc_rk4: out of memory")
        if check and status.any():
            model._raise_newton(status, np.array([ts[k]]), x)
        X[k + 1], D[k + 1] = x, d
    return X, D


#: batch rows x samples below which one thread does the whole batch (a thread costs ~0.1 ms)
_THREAD_WORK = 20_000


def _row_chunks(n: int, nt: int) -> list:
    """Contiguous row ranges ``(a, b)`` for the threads of :func:`_threaded`: one per thread
    (:func:`bondgraph.numerics.threads.worker_threads`), none smaller than one row."""
    from .threads import worker_threads

    k = min(n, worker_threads()) if n * nt >= _THREAD_WORK else 1
    edges = np.linspace(0, n, k + 1).round().astype(int)
    return list(zip(edges[:-1], edges[1:]))


def _threaded(args, chunks, x, z, zinit, d, p, sp, check, X, D, every) -> bool:
    """Rows `chunks` of the batch integrated by one thread each (the C loop releases the GIL;
    rows never interact, so the numbers are those of one call).  True when every chunk ran to
    the end; False, with `x`, `z` and `d` untouched, when one did not (a Newton failure or no memory:
    the caller runs the whole batch again to report it as one call would)."""
    from concurrent.futures import ThreadPoolExecutor

    nt = X.shape[0]
    parts = []
    for a, b in chunks:
        xc, zc, dc = (np.ascontiguousarray(v[a:b]) for v in (x, z, d))
        pc = p if sp == 0 else np.ascontiguousarray(p[a:b])
        Xc, Dc = np.empty((nt, *xc.shape)), np.empty((nt, *dc.shape))
        Xc[0], Dc[0] = xc, dc
        parts.append((xc, zc, dc, pc, np.zeros(b - a, dtype=np.intc), Xc, Dc))

    def one(part):
        xc, zc, dc, pc, sc, Xc, Dc = part
        return run_samples(*args, xc, zc, zinit, dc, pc, sp, sc, check, Xc, Dc, every)

    with ThreadPoolExecutor(max_workers=len(parts)) as pool:
        done = list(pool.map(one, parts))
    if any(k != nt - 1 for k in done):
        return False
    for (a, b), (xc, zc, dc, _, _, Xc, Dc) in zip(chunks, parts):
        for whole, part in ((x, xc), (z, zc), (d, dc)):
            if whole.size:              # (np.tile of zero columns is a read-only view)
                whole[a:b] = part
        X[:, a:b], D[:, a:b] = Xc, Dc
    return True
