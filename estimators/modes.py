"""Unobservable and uncontrollable modes (Popov-Belevitch-Hautus test), and
the detectability / stabilisability checks that the Riccati designs run
first, so that a bad pair is reported by its eigenvalue and state names
instead of a failed Riccati solve.

The PBH test: an eigenvalue :math:`\\lambda` of :math:`A` is unobservable
from :math:`C` iff

.. math:: \\operatorname{rank}\\begin{bmatrix} \\lambda I - A \\\\ C \\end{bmatrix} < n,

judged here by the smallest singular value of the stacked matrix with
:math:`A` and :math:`C` each scaled to unit 2-norm (so that the test does not
depend on the units of the outputs).  Uncontrollable modes are the
unobservable modes of the dual pair :math:`(A^T, B^T)`.

Examples
--------
A mass whose position is not measured (only its velocity) has an
unobservable rigid-body mode at 0:

>>> import numpy as np
>>> from estimators.modes import unobservable_modes
>>> modes = unobservable_modes(np.array([[0.0, 1.0], [0.0, -1.0]]), np.array([[0.0, 1.0]]))
>>> [round(m.eigenvalue.real, 12) for m in modes]
[0.0]
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from estimators.errors import UncontrollableModeError, UnobservableModeError

from ._linalg import as_matrix

__all__ = ["Mode", "unobservable_modes", "uncontrollable_modes", "check_detectable", "check_stabilizable"]

PBH_RTOL = 1e-9          # smallest singular value (scaled) below which a mode is lost
STABILITY_RTOL = 1e-10   # margin (times max(1, |A|)) by which a mode must be stable


@dataclass(frozen=True)
class Mode:
    """One eigenvalue of ``A`` that fails the PBH test.

    Attributes
    ----------
    eigenvalue : complex
        Continuous time: rad/s; discrete time: per sample.
    direction : ndarray, shape (n_states,)
        Unit-norm state direction (right singular vector of the PBH matrix);
        for an unobservable mode, the state combination the outputs do not see.
    residual : float
        Scaled smallest singular value of the PBH matrix (0 = exactly lost).
    """

    eigenvalue: complex
    direction: np.ndarray
    residual: float

    def describe(self, state_names: Sequence[str] | None = None) -> str:
        """The direction as ``0.99*theta_m + 0.0062*theta_sint + ...`` (largest entries first)."""
        v = self.direction
        names = list(state_names) if state_names is not None else [f"x{i}" for i in range(v.size)]
        order = np.argsort(-np.abs(v))
        big = [i for i in order if abs(v[i]) >= 1e-3 * np.max(np.abs(v))][:6]
        terms = [f"{_fmt(v[i])}*{names[i]}" for i in big]
        more = " + ..." if len(big) < np.count_nonzero(np.abs(v) > 1e-12 * np.max(np.abs(v))) else ""
        return " + ".join(terms).replace("+ -", "- ") + more

    def dominant_states(self, state_names: Sequence[str]) -> tuple[str, ...]:
        """Names whose entry in `direction` is at least 10 % of the largest."""
        v = np.abs(self.direction)
        return tuple(state_names[i] for i in np.argsort(-v) if v[i] >= 0.1 * v.max())


def _fmt(z) -> str:
    z = complex(z)
    return f"{z.real:.3g}" if abs(z.imag) <= 1e-12 * max(abs(z), 1e-300) else f"({z:.3g})"


def _eig_str(lam: complex) -> str:
    return _fmt(lam)


def _pbh_modes(A: np.ndarray, C: np.ndarray, rtol: float) -> list[Mode]:
    n = A.shape[0]
    if n == 0:
        return []
    sA = max(np.linalg.norm(A, 2), 1e-300)
    sC = np.linalg.norm(C, 2) if C.size else 0.0
    Cs = C / sC if sC > 0 else np.zeros((0, n))
    modes: list[Mode] = []
    for lam in np.linalg.eigvals(A):
        if lam.imag < 0 and any(abs(lam.conjugate() - m.eigenvalue) < 1e-9 * sA for m in modes):
            continue  # report a complex pair once
        if any(abs(lam - m.eigenvalue) <= 1e-9 * sA for m in modes):
            continue  # repeated eigenvalue already reported
        M = np.vstack([(lam * np.eye(n) - A) / sA, Cs.astype(complex)])
        _, s, vh = np.linalg.svd(M)
        if s[-1] < rtol:
            v = vh[-1].conj()
            k = int(np.argmax(np.abs(v)))
            v = v * (abs(v[k]) / v[k])  # largest entry real positive
            v = v.real if np.max(np.abs(v.imag)) <= 1e-12 else v
            modes.append(Mode(complex(lam), v, float(s[-1])))
    return modes


def unobservable_modes(A, C, *, rtol: float = PBH_RTOL) -> list[Mode]:
    """Eigenvalues of ``A`` that the outputs ``y = C x`` do not see (PBH test).

    Parameters
    ----------
    A : array_like, shape (n, n)
    C : array_like, shape (p, n)
    rtol : float
        Threshold on the scaled smallest singular value of ``[lambda I - A; C]``.

    Returns
    -------
    list of Mode
        Empty when ``(A, C)`` is observable.  A complex pair is reported once.
    """
    A = as_matrix(A, "A", (None, None))
    C = as_matrix(C, "C", (None, A.shape[0]))
    return _pbh_modes(A, C, rtol)


def uncontrollable_modes(A, B, *, rtol: float = PBH_RTOL) -> list[Mode]:
    """Eigenvalues of ``A`` that the inputs ``B`` cannot move (PBH test on ``(A^T, B^T)``).

    The `direction` of each mode is then a left eigenvector of ``A``: the
    state combination :math:`w^T x` that the inputs do not reach.
    """
    A = as_matrix(A, "A", (None, None))
    B = as_matrix(B, "B", (A.shape[0], None))
    return _pbh_modes(A.T, B.T, rtol)


def _is_stable(lam: complex, A: np.ndarray, discrete: bool) -> bool:
    margin = STABILITY_RTOL * max(1.0, np.linalg.norm(A, 2))
    return abs(lam) < 1.0 - STABILITY_RTOL if discrete else lam.real < -margin


def check_detectable(A, C, *, discrete: bool, state_names: Sequence[str] | None = None,
                     rtol: float = PBH_RTOL, owner: str = "") -> None:
    """Raise :class:`~bondgraph.errors.UnobservableModeError` for the first
    unobservable mode that is not stable (``Re < 0``, or ``|z| < 1`` when
    `discrete`); stable unobservable modes are allowed (detectability).

    The message names the eigenvalue and the invisible state combination
    (with `state_names` when given).
    """
    A = as_matrix(A, "A", (None, None), owner=owner)
    C = as_matrix(C, "C", (None, A.shape[0]), owner=owner)
    for mode in _pbh_modes(A, C, rtol):
        if not _is_stable(mode.eigenvalue, A, discrete):
            where = f"{owner}: " if owner else ""
            kind = "|z| >= 1" if discrete else "Re >= 0"
            names = tuple(state_names) if state_names is not None else None
            raise UnobservableModeError(
                f"{where}the pair (A, C) is not detectable: the mode with eigenvalue "
                f"{_eig_str(mode.eigenvalue)} ({kind}, not stable) is unobservable; the measurements do "
                f"not see the state combination {mode.describe(names)}. Measure it, or remove it from "
                f"the model (e.g. use relative instead of absolute angles)",
                mode.eigenvalue, mode.direction, mode.dominant_states(names) if names else ())


def check_stabilizable(A, B, *, discrete: bool, state_names: Sequence[str] | None = None,
                       rtol: float = PBH_RTOL, owner: str = "") -> None:
    """Raise :class:`~bondgraph.errors.UncontrollableModeError` for the first
    uncontrollable mode that is not stable (stabilisability)."""
    A = as_matrix(A, "A", (None, None), owner=owner)
    B = as_matrix(B, "B", (A.shape[0], None), owner=owner)
    for mode in _pbh_modes(A.T, B.T, rtol):
        if not _is_stable(mode.eigenvalue, A, discrete):
            where = f"{owner}: " if owner else ""
            kind = "|z| >= 1" if discrete else "Re >= 0"
            names = tuple(state_names) if state_names is not None else None
            raise UncontrollableModeError(
                f"{where}the pair (A, B) is not stabilisable: the mode with eigenvalue "
                f"{_eig_str(mode.eigenvalue)} ({kind}, not stable) is uncontrollable; the inputs do not "
                f"reach the state combination {mode.describe(names)}",
                mode.eigenvalue, mode.direction, mode.dominant_states(names) if names else ())
