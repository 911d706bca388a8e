"""The feature regression of a drifting nominal, restarted: each segment's start state a nuisance.

Where the nominal model integrates what it leaves out (a force-driven carriage without its
friction), its residual over the training part is mostly drift: the integral of the missing
effort, and for a position the integral of that.  Regressed on that residual
(:mod:`diagnosis.features`), any feature whose double integral follows the drift explains it:
on a carriage with a Coulomb + viscous friction and a constant load, a quadratic drag, a cubic
spring, a relaxation and a viscous friction each explained 99.2-99.3 % and the right pair was
not selected (``python -m diagnosis.benchmark.ball_screw``, seed 12, case 005).  The held-out
judge of such a nominal is the segment error (:mod:`diagnosis.segments`), which restarts every
segment from a state fitted to the data, so that stopping the drift alone earns nothing.

The regression is restarted the same way.  Along the linearised run
(:class:`~diagnosis.graph_location_linear.LinearisedResponse`) the residual at a sample of segment
:math:`k` (starting at sample :math:`t_k`) is

.. math::

    r(t) = C(t)\\,\\Phi(t, t_k)\\,\\delta x_k + \\sum_j S_j(t)\\,\\beta_j + \\text{noise},

where :math:`\\delta x_k` is the state deviation at :math:`t_k`, free per segment: the response
of a feature injected since the record's start, :math:`S_j`, differs from its response injected
since :math:`t_k` by a free response from :math:`t_k`, which :math:`\\delta x_k` takes up.  So
projecting each segment's weighted residual and responses onto the complement of its free
responses :math:`C\\Phi(t, t_k)` is the least-squares fit with every segment's start state
fitted too (generalised least squares with nuisance parameters, exact for a linear model),
and what is left is what each segment's restarted prediction leaves.  The segments are then
independent, so the regression is validated across them (every third segment held out in turn)
rather than on the record's last rows: a carriage that runs one way in the first 70 % and the other
way after confounds a Coulomb level with a constant load on the fit rows alone.
"""
from __future__ import annotations

import numpy as np

__all__ = ["restarted", "free_responses", "FOLDS"]

#: validation folds the segments are dealt into, in turn (segment i in fold i mod FOLDS)
FOLDS = 3


def free_responses(lin, rows, starts) -> np.ndarray:
    """The outputs' responses at `rows` to a unit deviation of each state at the start of the
    rows' segment: ``(n_rows, n_outputs, n_states)``.

    `lin` is a :class:`~diagnosis.graph_location_linear.LinearisedResponse`; `starts` the sample
    indices segments start at (the first is 0).
    """
    n, nx = lin.C.shape[0], lin.n_states
    out = np.zeros((len(rows), lin.C.shape[1], nx))
    keep = np.full(n, -1)
    keep[np.asarray(rows, int)] = np.arange(len(rows))
    begin = np.zeros(n, dtype=bool)
    begin[np.asarray(starts, int)] = True
    M = np.eye(nx)
    for k in range(n):
        if begin[k]:
            M = np.eye(nx)
        if keep[k] >= 0:
            out[keep[k]] = lin.C[k] @ M
        if k < n - 1:
            M = lin.Phi[k] @ M
    return out


def restarted(lin, rows, length: int, r, S, sw):
    """`r` (rows, ny) and `S` (rows, ny, m) with every segment's free responses projected out, and
    the segments dealt round into :data:`FOLDS` validation folds.

    Parameters
    ----------
    lin : LinearisedResponse
        The run's linearisation (its sample grid holds `rows`).
    rows : ndarray of int
        The kept sample indices.
    length : int
        Samples per segment (the segment judge's, :attr:`~diagnosis.restarts.SegmentPlan.length`).
    r, S : ndarray
        Residual and feature responses at the rows, output units.
    sw : ndarray, shape (ny,)
        Square-root weights, 1/sigma.

    Returns
    -------
    (r, S, lost, folds)
        The projected residual and responses (output units), the degrees of freedom the start
        states took (the noise left is that many variances less), and each row's fold
        (``regress_kinds``' `folds`).  With fewer than :data:`FOLDS` segments, `r` and `S`
        unchanged, 0 and None (the regression's time split).
    """
    rows = np.asarray(rows, int)
    n_rows = rows.size
    step = max(int(rows[1] - rows[0]), 1) if n_rows > 1 else 1
    per = max(int(length) // step, 2)
    cuts = list(range(0, n_rows, per))
    if len(cuts) > 1 and n_rows - cuts[-1] < per // 2:     # a short tail joins the segment before
        cuts.pop()
    if len(cuts) < FOLDS:
        return r, S, 0, None
    N = free_responses(lin, rows, rows[cuts])
    r, S = np.array(r, float), np.array(S, float)
    ny, m = r.shape[1], S.shape[2]
    lost, folds = 0, np.zeros(n_rows, dtype=int)
    for i, (a, b) in enumerate(zip(cuts, cuts[1:] + [n_rows])):
        folds[a:b] = i % FOLDS
        A = (N[a:b] * sw[None, :, None]).reshape(-1, N.shape[2])
        U, sv, _ = np.linalg.svd(A, full_matrices=False)
        U = U[:, sv > 1e-9 * sv[0]] if sv.size and sv[0] > 0 else U[:, :0]
        rb = (r[a:b] * sw[None, :]).reshape(-1)
        Sb = (S[a:b] * sw[None, :, None]).reshape(-1, m)
        r[a:b] = (rb - U @ (U.T @ rb)).reshape(b - a, ny) / sw[None, :]
        S[a:b] = (Sb - U @ (U.T @ Sb)).reshape(b - a, ny, m) / sw[None, :, None]
        lost += U.shape[1]
    return r, S, lost, folds
