"""Linear-quadratic regulators: continuous :func:`lqr` and discrete
:func:`dlqr` (with integral action: :mod:`estimators.lqi`).

Both check stabilisability first and name an uncontrollable unstable mode
(:class:`~bondgraph.errors.UncontrollableModeError`) instead of failing
inside the Riccati solver; python-control's ``lqr``/``dlqr`` give the same
gains (tested to 1e-9).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
import scipy.linalg

from estimators.errors import EstimatorError

from ._linalg import as_matrix, check_covariance, riccati_call
from .modes import check_stabilizable

__all__ = ["LQRGain", "lqr", "dlqr"]

@dataclass(frozen=True)
class LQRGain:
    """Result of :func:`lqr` / :func:`dlqr`.

    Attributes
    ----------
    K : ndarray, shape (m, n)
        Gain of ``u = -K x``.
    S : ndarray, shape (n, n)
        Riccati solution (cost-to-go ``x^T S x``).
    poles : ndarray, shape (n,)
        Closed-loop eigenvalues of ``A - B K`` (rad/s, or per sample).
    discrete : bool
    """

    K: np.ndarray
    S: np.ndarray
    poles: np.ndarray
    discrete: bool


def check_weights(A, B, Q, R, N, owner):
    """`A`, `B`, `Q`, `R`, `N` as float matrices of matching shapes, checked (square `A`, `Q`
    symmetric PSD, `R` positive definite, the joint cost convex); `N` defaults to zeros.
    Errors name `owner` (the calling function)."""
    A = as_matrix(A, "A", (None, None), owner=owner)
    n = A.shape[0]
    if A.shape != (n, n):
        raise EstimatorError(f"{owner}: A: expected a square matrix but found shape {A.shape}", name="A")
    B = as_matrix(B, "B", (n, None), owner=owner)
    m = B.shape[1]
    Q = check_covariance(Q, "Q", n, definite=False, owner=owner)
    R = check_covariance(R, "R", m, definite=True, owner=owner)
    if N is None:
        N = np.zeros((n, m))
    else:
        N = as_matrix(N, "N", (n, m), owner=owner)
        # the cost must be convex: [[Q, N], [N^T, R]] PSD
        check_covariance(np.block([[Q, N], [N.T, R]]), "[[Q, N], [N^T, R]]", n + m, definite=False, owner=owner)
    return A, B, Q, R, N


def solve_riccati(A, B, Q, R, N, *, discrete, owner, state_names=None) -> LQRGain:
    """The LQR gain of checked weights (:func:`check_weights`): the continuous or discrete
    algebraic Riccati equation's solution `S`, the gain `K` and the closed-loop poles."""
    check_stabilizable(A, B, discrete=discrete, state_names=state_names, owner=owner)
    if discrete:
        S = riccati_call(scipy.linalg.solve_discrete_are, A, B, Q, R, None, N, what=owner)
        # K = (B^T S B + R)^-1 (B^T S A + N^T)
        K = scipy.linalg.solve(B.T @ S @ B + R, B.T @ S @ A + N.T, assume_a="pos")
    else:
        S = riccati_call(scipy.linalg.solve_continuous_are, A, B, Q, R, None, N, what=owner)
        K = scipy.linalg.solve(R, B.T @ S + N.T, assume_a="pos")   # K = R^-1 (B^T S + N^T)
    poles = np.linalg.eigvals(A - B @ K)
    unstable = np.max(np.abs(poles)) >= 1.0 if discrete else np.max(poles.real) >= 0.0
    if poles.size and unstable:
        raise EstimatorError(f"{owner}: the closed loop is not stable (poles {np.round(poles, 6)}); check that "
                             f"(Q, A) has no unobservable mode on the stability boundary", name="Q")
    return LQRGain(K, S, poles, discrete)


def lqr(A, B, Q, R, *, N=None, state_names: Sequence[str] | None = None) -> LQRGain:
    """Continuous-time LQR.

    Minimises :math:`\\int_0^\\infty x^T Q x + u^T R u + 2 x^T N u \\, dt`
    for :math:`\\dot x = A x + B u`:

    .. math::

        A^T S + S A - (S B + N) R^{-1} (B^T S + N^T) + Q = 0, \\qquad
        K = R^{-1}(B^T S + N^T)

    Parameters
    ----------
    A : array_like, shape (n, n)
    B : array_like, shape (n, m)
    Q : array_like, shape (n, n)
        State weight, symmetric PSD.
    R : array_like, shape (m, m)
        Input weight, symmetric PD.
    N : array_like, shape (n, m), optional
        Cross weight.
    state_names : sequence of str, optional
        For the error message of an unstabilisable pair.

    Returns
    -------
    LQRGain
        ``K`` and ``S`` equal python-control's ``lqr(A, B, Q, R)``.
    """
    A, B, Q, R, N = check_weights(A, B, Q, R, N, "lqr")
    return solve_riccati(A, B, Q, R, N, discrete=False, owner="lqr", state_names=state_names)


def dlqr(F, G, Q, R, *, N=None, state_names: Sequence[str] | None = None) -> LQRGain:
    """Discrete-time LQR for :math:`x_{k+1} = F x_k + G u_k`.

    .. math::

        S = F^T S F - (F^T S G + N)(G^T S G + R)^{-1}(G^T S F + N^T) + Q, \\qquad
        K = (G^T S G + R)^{-1}(G^T S F + N^T)

    Parameters and returns as :func:`lqr` (python-control's ``dlqr``).
    """
    F, G, Q, R, N = check_weights(F, G, Q, R, N, "dlqr")
    return solve_riccati(F, G, Q, R, N, discrete=True, owner="dlqr", state_names=state_names)
