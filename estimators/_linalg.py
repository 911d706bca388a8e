"""Private helpers of the linear estimators and controllers: matrix
validation with errors that name the matrix, and the zero-order-hold
discretisation by the matrix exponential.
"""
from __future__ import annotations

import numpy as np
import scipy.linalg

from estimators.errors import EstimatorError

__all__ = ["as_matrix", "as_vector", "check_covariance", "zoh", "riccati_call"]

# Relative tolerance for symmetry (entries) and for semi-definiteness (eigenvalues).
SYMMETRY_RTOL = 1e-10
DEFINITE_RTOL = 1e-12


def as_matrix(value, name: str, shape: tuple[int | None, int | None], *, owner: str = "") -> np.ndarray:
    """A finite float matrix of the given shape (``None`` = any size), or an error naming it.

    A scalar is accepted as a (1, 1) matrix (and only fits where (1, 1) is expected).
    """
    where = f"{owner}: " if owner else ""
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise EstimatorError(f"{where}{name} is not a real matrix ({exc})", name=name) from None
    if arr.ndim == 0:
        arr = arr.reshape(1, 1)
    expected = "(" + ", ".join("any" if s is None else str(s) for s in shape) + ")"
    if arr.ndim != 2 or any(s is not None and s != a for s, a in zip(shape, arr.shape)):
        raise EstimatorError(f"{where}{name}: expected shape {expected} but found {arr.shape}", name=name)
    if not np.all(np.isfinite(arr)):
        bad = tuple(int(i) for i in np.argwhere(~np.isfinite(arr))[0])
        raise EstimatorError(f"{where}{name} has a non-finite entry at {bad}: {arr[bad]}", name=name)
    return arr


def as_vector(value, name: str, n: int, *, owner: str = "") -> np.ndarray:
    """A finite float vector of length ``n`` (a (n, 1) or (1, n) matrix is flattened)."""
    where = f"{owner}: " if owner else ""
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise EstimatorError(f"{where}{name} is not a real vector ({exc})", name=name) from None
    if arr.ndim == 0 or (arr.ndim == 2 and 1 in arr.shape):
        arr = arr.reshape(-1)
    if arr.shape != (n,):
        raise EstimatorError(f"{where}{name}: expected shape ({n},) but found {arr.shape}", name=name)
    if not np.all(np.isfinite(arr)):
        raise EstimatorError(f"{where}{name} has a non-finite entry: {arr}", name=name)
    return arr


def check_covariance(value, name: str, n: int, *, definite: bool, owner: str = "") -> np.ndarray:
    """A symmetric positive semi-definite (``definite=False``) or positive
    definite (``definite=True``) ``(n, n)`` matrix, symmetrised exactly.

    Raises
    ------
    EstimatorError
        Naming the matrix: wrong shape, non-finite, not symmetric (largest
        asymmetry given), not PSD/PD (smallest eigenvalue given).
    """
    where = f"{owner}: " if owner else ""
    M = as_matrix(value, name, (n, n), owner=owner)
    scale = float(np.max(np.abs(M))) if M.size else 0.0
    asym = float(np.max(np.abs(M - M.T))) if M.size else 0.0
    if asym > SYMMETRY_RTOL * max(scale, np.finfo(float).tiny):
        i, j = np.unravel_index(np.argmax(np.abs(M - M.T)), M.shape)
        raise EstimatorError(f"{where}{name} must be symmetric; {name}[{i},{j}] = {M[i, j]:.6g} but "
                             f"{name}[{j},{i}] = {M[j, i]:.6g}", name=name)
    M = 0.5 * (M + M.T)
    if n == 0:
        return M
    eig = np.linalg.eigvalsh(M)
    tol = DEFINITE_RTOL * n * max(scale, np.finfo(float).tiny)
    if definite and (eig[0] <= tol or not _cholesky_ok(M)):
        raise EstimatorError(f"{where}{name} must be symmetric positive definite; its smallest eigenvalue "
                             f"is {eig[0]:.6g} (expected > 0)", name=name)
    if not definite and eig[0] < -tol:
        raise EstimatorError(f"{where}{name} must be symmetric positive semi-definite; its smallest "
                             f"eigenvalue is {eig[0]:.6g} (expected >= 0)", name=name)
    return M


def _cholesky_ok(M: np.ndarray) -> bool:
    try:
        np.linalg.cholesky(M)
    except np.linalg.LinAlgError:
        return False
    return True


def zoh(A: np.ndarray, B: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Exact zero-order-hold discretisation.

    .. math::

        \\exp\\left(\\begin{bmatrix} A & B \\\\ 0 & 0 \\end{bmatrix} T\\right)
        = \\begin{bmatrix} A_d & B_d \\\\ 0 & I \\end{bmatrix},
        \\qquad A_d = e^{AT},\\quad B_d = \\int_0^T e^{A\\tau} d\\tau\\, B

    Parameters
    ----------
    A : ndarray, shape (n, n)
    B : ndarray, shape (n, m)
    dt : float, s
        Sampling period ``T`` (> 0).

    Returns
    -------
    Ad : ndarray, shape (n, n)
    Bd : ndarray, shape (n, m)
    """
    dt = float(dt)
    if not np.isfinite(dt) or dt <= 0.0:
        raise EstimatorError(f"sampling period dt must be a finite number > 0 s, got {dt!r}", name="dt")
    n, m = B.shape
    M = np.zeros((n + m, n + m))
    M[:n, :n] = A
    M[:n, n:] = B
    E = scipy.linalg.expm(M * dt)
    return E[:n, :n], E[:n, n:]


def riccati_call(solver, *args, what: str) -> np.ndarray:
    """Call a scipy Riccati solver; turn its failures into an :class:`EstimatorError`."""
    try:
        X = solver(*args)
    except (np.linalg.LinAlgError, ValueError) as exc:
        raise EstimatorError(f"{what}: the Riccati equation has no stabilising solution ({exc})") from None
    if not np.all(np.isfinite(X)):
        raise EstimatorError(f"{what}: the Riccati solution is not finite")
    return 0.5 * (X + X.T)
