"""Validation of estimator arguments: vectors and covariance matrices, every problem collected.

Each check returns the converted array and appends a message to ``problems``
instead of raising, so that a constructor can report all bad arguments at once
(:func:`raise_problems`).
"""
from __future__ import annotations

import numpy as np

from estimators.errors import EstimatorError

from .sigma_points import SigmaPoints

__all__ = ["check_vector", "check_covariance", "raise_problems", "validate_setup", "SYMMETRY_RTOL"]

#: Relative tolerance of the symmetry check: :math:`|M - M^T| \\le 10^{-9} \\max|M|`.
SYMMETRY_RTOL = 1e-9


def _labels(names) -> str:
    return f" ({', '.join(names)})" if names else ""


def check_vector(name: str, value, n: int, problems: list, *, names=()) -> np.ndarray | None:
    """`value` as a finite float vector of length `n`, or None with a problem appended."""
    try:
        v = np.array(value, dtype=float)
    except (TypeError, ValueError):
        problems.append(f"{name}: not an array of numbers: {value!r}")
        return None
    if v.shape != (n,):
        problems.append(f"{name}: expected shape ({n},){_labels(names)}; found {v.shape}")
        return None
    bad = [names[i] if i < len(names) else str(i) for i in np.flatnonzero(~np.isfinite(v))]
    if bad:
        problems.append(f"{name}: non-finite entries {', '.join(bad)}")
        return None
    return v


def check_covariance(name: str, value, n: int, problems: list, *, definite: bool,
                     names=()) -> np.ndarray | None:
    """`value` as a finite symmetric positive (semi)definite `n` x `n` matrix.

    Parameters
    ----------
    name : str
        Argument name used in messages (``"P0"``, ``"Q"``, ``"R"``).
    value : array_like
    n : int
    problems : list of str
        Messages are appended here.
    definite : bool
        True: positive definite (Cholesky must succeed); False: positive
        semidefinite (eigenvalues :math:`\\ge -10^{-12} \\max|\\lambda|`).
    names : sequence of str
        Names of the rows (states, measurements), for the messages.

    Returns
    -------
    ndarray, shape (n, n), symmetrised, or None when there is a problem.
    """
    try:
        M = np.array(value, dtype=float)
    except (TypeError, ValueError):
        problems.append(f"{name}: not an array of numbers")
        return None
    if M.shape != (n, n):
        problems.append(f"{name}: expected shape ({n}, {n}){_labels(names)}; found {M.shape}")
        return None
    if not np.isfinite(M).all():
        problems.append(f"{name}: has non-finite entries (NaN or inf)")
        return None
    scale = float(np.abs(M).max()) if M.size else 0.0
    asym = float(np.abs(M - M.T).max()) if M.size else 0.0
    if asym > SYMMETRY_RTOL * scale:
        i, j = np.unravel_index(np.argmax(np.abs(M - M.T)), M.shape)
        problems.append(f"{name}: not symmetric ({name}[{i},{j}] = {M[i, j]!r} but "
                        f"{name}[{j},{i}] = {M[j, i]!r})")
        return None
    M = 0.5 * (M + M.T)
    if definite:
        try:
            np.linalg.cholesky(M)
        except np.linalg.LinAlgError:
            low = float(np.linalg.eigvalsh(M).min())
            problems.append(f"{name}: not positive definite (smallest eigenvalue {low:.6g})")
            return None
    else:
        eig = np.linalg.eigvalsh(M)
        if eig.size and eig.min() < -1e-12 * max(float(np.abs(eig).max()), 1e-300):
            problems.append(f"{name}: not positive semidefinite (smallest eigenvalue {eig.min():.6g})")
            return None
    return M


def raise_problems(problems: list, what: str) -> None:
    """Raise one :class:`EstimatorError` listing every problem (``name`` = the first one's)."""
    if problems:
        first = problems[0].split(":", 1)[0]
        n = len(problems)
        raise EstimatorError(f"{what}: {n} problem{'s' if n != 1 else ''}:\n"
                             + "\n".join(f"  - {p}" for p in problems), first, problems=problems)


def validate_setup(points, x0, P0, Q, R, n, m, state_names, measurement_names):
    """Checked ``x0, P0, Q, R`` of a UKF with n states and m measurements (m None: R is not
    a matrix); raises one :class:`EstimatorError` listing every problem."""
    if not isinstance(points, SigmaPoints):
        raise EstimatorError("points must be a SigmaPoints object (JulierSigmaPoints, "
                             f"MerweScaledSigmaPoints); found {type(points).__name__}", "points")
    problems = []
    if points.n != n:
        problems.append(f"points: made for n = {points.n} states; the filter has {n}")
    x0 = check_vector("x0", x0, n, problems, names=state_names)
    P0 = check_covariance("P0", P0, n, problems, definite=True, names=state_names)
    Q = check_covariance("Q", Q, n, problems, definite=False, names=state_names)
    if m is None:
        problems.append(f"R: expected a square matrix (m, m); found shape {np.shape(R)}")
    else:
        R = check_covariance("R", R, m, problems, definite=True, names=measurement_names)
    raise_problems(problems, "UKF set-up")
    return x0, P0, Q, R
