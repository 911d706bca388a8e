"""LQR with single or double integral action (LQI): continuous :func:`lqi`,
discrete :func:`dlqi`, the augmentations they solve, and the stateful
:class:`LQIController` that runs an LQI gain.

Integral action follows eqs. (10)-(13) of [1]_: for the chosen outputs
:math:`y_z = C_z x + D_z u` with reference :math:`r`,

.. math::

    \\dot z = r - C_z x - D_z u, \\qquad \\dot w = z \\quad \\text{(double action only)},

    u = -K_x x - K_z z - K_{zz} w

so that, in the paper's names (eqs. (11), (13), (16)-(17)),
:math:`K_x = F'_{ix}`, :math:`K_z = F'_{iz}` and :math:`K_{zz} = F_{iz}`.
With the error taken as reference minus output, a plant whose output rises
with ``u`` gets negative integral gains, as the paper's
:math:`F'_{iz} = -3.16`, :math:`F_{iz} = -70.71`.

In discrete time (period ``dt``) the integrators are forward-Euler sums of
the same quantities, :math:`z_{k+1} = z_k + dt\\,(r_k - C_z x_k - D_z u_k)`,
:math:`w_{k+1} = w_k + dt\\, z_k`, so discrete and continuous gains on ``z``
and ``w`` have the same units.

All designs check stabilisability first and name an uncontrollable unstable
mode (:class:`~bondgraph.errors.UncontrollableModeError`), e.g. an integral
that the inputs cannot drive because the plant has a zero at ``s = 0``.
python-control's ``lqr``/``dlqr`` give the same gains (tested to 1e-9).

References
----------
.. [1] Exoskeleton bond graph / Kalman observer paper,
   seed 004 (``docs/references.md``), Section 5.2, eqs. (10)-(17).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, Sequence

import numpy as np

from estimators.errors import EstimatorError

from ._linalg import as_matrix, as_vector
from .lqr import solve_riccati, check_weights

__all__ = ["LQIGain", "lqi", "dlqi", "augment_integral", "augment_integral_discrete", "LQIController"]


@dataclass(frozen=True)
class LQIGain:
    """Result of :func:`lqi` / :func:`dlqi`: the augmented design, split.

    Attributes
    ----------
    K : ndarray, shape (m, n + order * nz)
        Full gain on ``[x; z; w]``.
    Kx : ndarray, shape (m, n)
        State part (:math:`F'_{ix}` of [1]_).
    Kz : ndarray, shape (m, nz)
        First-integral part (:math:`F'_{iz}`).
    Kzz : ndarray, shape (m, nz) or None
        Second-integral part (:math:`F_{iz}`); None for single integral action.
    S : ndarray
        Riccati solution of the augmented problem.
    poles : ndarray
        Closed-loop eigenvalues of the augmented system.
    A_aug, B_aug, E_aug : ndarray
        Augmented state, input and reference matrices.
    Cz, Dz : ndarray
        The integrated outputs ``y_z = Cz x + Dz u``.
    order : {1, 2}
    discrete : bool
    dt : float or None, s
        Sampling period of a discrete design.
    """

    K: np.ndarray
    Kx: np.ndarray
    Kz: np.ndarray
    Kzz: np.ndarray | None
    S: np.ndarray
    poles: np.ndarray
    A_aug: np.ndarray
    B_aug: np.ndarray
    E_aug: np.ndarray
    Cz: np.ndarray
    Dz: np.ndarray
    order: int
    discrete: bool
    dt: float | None = None

    @property
    def Fix(self) -> np.ndarray:
        """:math:`F'_{ix}` of eqs. (11), (13), (16) of [1]_: same as `Kx`."""
        return self.Kx

    @property
    def Fiz_prime(self) -> np.ndarray:
        """:math:`F'_{iz}` of eqs. (11), (13), (17) of [1]_: same as `Kz`."""
        return self.Kz

    @property
    def Fiz(self) -> np.ndarray | None:
        """:math:`F_{iz}` of eqs. (13), (17) of [1]_: same as `Kzz`."""
        return self.Kzz


def _augment(A, B, Cz, Dz, order, owner):
    A = as_matrix(A, "A", (None, None), owner=owner)
    n = A.shape[0]
    B = as_matrix(B, "B", (n, None), owner=owner)
    m = B.shape[1]
    Cz = as_matrix(Cz, "Cz", (None, n), owner=owner)
    nz = Cz.shape[0]
    Dz = np.zeros((nz, m)) if Dz is None else as_matrix(Dz, "Dz", (nz, m), owner=owner)
    if order not in (1, 2):
        raise EstimatorError(f"{owner}: order must be 1 (single) or 2 (double integral action), got {order!r}",
                             name="order")
    return A, B, Cz, Dz, n, m, nz


def augment_integral(A, B, Cz, *, order: Literal[1, 2] = 1, Dz=None):
    """Continuous augmentation with integrals of ``e = r - Cz x - Dz u`` (eqs. (10), (12) of [1]_).

    .. math::

        \\frac{d}{dt}\\begin{bmatrix} x \\\\ z \\\\ w \\end{bmatrix} =
        \\begin{bmatrix} A & 0 & 0 \\\\ -C_z & 0 & 0 \\\\ 0 & I & 0 \\end{bmatrix}
        \\begin{bmatrix} x \\\\ z \\\\ w \\end{bmatrix}
        + \\begin{bmatrix} B \\\\ -D_z \\\\ 0 \\end{bmatrix} u
        + \\begin{bmatrix} 0 \\\\ I \\\\ 0 \\end{bmatrix} r

    (``w`` rows only for ``order=2``).

    Returns
    -------
    A_aug : ndarray, shape (n + order nz, n + order nz)
    B_aug : ndarray, shape (n + order nz, m)
    E_aug : ndarray, shape (n + order nz, nz)
    """
    A, B, Cz, Dz, n, m, nz = _augment(A, B, Cz, Dz, order, "augment_integral")
    return _blocks(A, B, Cz, Dz, order, n, m, nz, step=1.0, discrete=False)


def augment_integral_discrete(F, G, Cz, *, dt: float, order: Literal[1, 2] = 1, Dz=None):
    """Discrete augmentation: :math:`z_{k+1} = z_k + dt\\,(r_k - C_z x_k - D_z u_k)`,
    :math:`w_{k+1} = w_k + dt\\, z_k`.

    .. math::

        F_{aug} = \\begin{bmatrix} F & 0 & 0 \\\\ -dt\\,C_z & I & 0 \\\\ 0 & dt\\,I & I \\end{bmatrix},
        \\quad G_{aug} = \\begin{bmatrix} G \\\\ -dt\\,D_z \\\\ 0 \\end{bmatrix},
        \\quad E_{aug} = \\begin{bmatrix} 0 \\\\ dt\\,I \\\\ 0 \\end{bmatrix}

    Parameters
    ----------
    dt : float, s
        Sampling period.
    """
    F, G, Cz, Dz, n, m, nz = _augment(F, G, Cz, Dz, order, "augment_integral_discrete")
    dt = _check_dt(dt, "augment_integral_discrete")
    return _blocks(F, G, Cz, Dz, order, n, m, nz, step=dt, discrete=True)


def _check_dt(dt, owner) -> float:
    try:
        dt = float(dt)
    except (TypeError, ValueError):
        dt = float("nan")
    if not np.isfinite(dt) or dt <= 0:
        raise EstimatorError(f"{owner}: dt must be a finite number > 0 s", name="dt")
    return dt


def _blocks(A, B, Cz, Dz, order, n, m, nz, *, step, discrete):
    na = n + order * nz
    Aa, Ba, Ea = np.zeros((na, na)), np.zeros((na, m)), np.zeros((na, nz))
    Aa[:n, :n], Ba[:n] = A, B
    Aa[n:n + nz, :n], Ba[n:n + nz], Ea[n:n + nz] = -step * Cz, -step * Dz, step * np.eye(nz)
    if discrete:
        Aa[n:, n:] += np.eye(na - n)
    if order == 2:
        Aa[n + nz:, n:n + nz] = step * np.eye(nz)
    return Aa, Ba, Ea


def _aug_names(state_names, n, nz, order):
    base = list(state_names) if state_names is not None else [f"x{i}" for i in range(n)]
    names = base + [f"int_e{i}" for i in range(nz)]
    return names + [f"int_int_e{i}" for i in range(nz)] if order == 2 else names


def _lqi(Aa, Ba, Ea, Cz, Dz, Q, R, N, order, n, nz, *, discrete, dt, owner, state_names):
    Aa, Ba, Q, R, N = check_weights(Aa, Ba, Q, R, N, owner)
    g = solve_riccati(Aa, Ba, Q, R, N, discrete=discrete, owner=owner,
               state_names=_aug_names(state_names, n, nz, order))
    K = g.K
    return LQIGain(K, K[:, :n], K[:, n:n + nz], K[:, n + nz:] if order == 2 else None, g.S, g.poles,
                   Aa, Ba, Ea, Cz, Dz, order, discrete, dt)


def lqi(A, B, Cz, Q, R, *, order: Literal[1, 2] = 1, Dz=None, N=None,
        state_names: Sequence[str] | None = None) -> LQIGain:
    """Continuous LQR with single (``order=1``, eqs. (10)-(11) of [1]_) or
    double (``order=2``, eqs. (12)-(13)) integral action on ``y_z = Cz x + Dz u``.

    Parameters
    ----------
    A : array_like, shape (n, n)
    B : array_like, shape (n, m)
    Cz : array_like, shape (nz, n)
        Rows of the outputs to integrate (e.g. ``C[[i]]`` of a LinearModel).
    Q : array_like, shape (n + order nz, n + order nz)
        Weight on ``[x; z; w]`` (eq. (14): 7x7, eq. (15): 8x8 for the exoskeleton).
    R : array_like, shape (m, m)
    order : {1, 2}
    Dz : array_like, shape (nz, m), optional
    N : array_like, optional
        Cross weight on the augmented state and ``u``.
    state_names : sequence of str, optional
        Names of ``x`` (the integrals are called ``int_e<i>``, ``int_int_e<i>``).

    Returns
    -------
    LQIGain
    """
    A, B, Cz, Dz, n, m, nz = _augment(A, B, Cz, Dz, order, "lqi")
    Aa, Ba, Ea = _blocks(A, B, Cz, Dz, order, n, m, nz, step=1.0, discrete=False)
    return _lqi(Aa, Ba, Ea, Cz, Dz, Q, R, N, order, n, nz, discrete=False, dt=None, owner="lqi",
                state_names=state_names)


def dlqi(F, G, Cz, Q, R, *, dt: float, order: Literal[1, 2] = 1, Dz=None, N=None,
         state_names: Sequence[str] | None = None) -> LQIGain:
    """Discrete LQR with single or double integral action
    (:func:`augment_integral_discrete`); parameters as :func:`lqi` plus
    ``dt`` (s), the sampling period of ``(F, G)``."""
    F, G, Cz, Dz, n, m, nz = _augment(F, G, Cz, Dz, order, "dlqi")
    dt = _check_dt(dt, "dlqi")
    Aa, Ba, Ea = _blocks(F, G, Cz, Dz, order, n, m, nz, step=dt, discrete=True)
    return _lqi(Aa, Ba, Ea, Cz, Dz, Q, R, N, order, n, nz, discrete=True, dt=dt, owner="dlqi",
                state_names=state_names)


class LQIController:
    """Runs an :class:`LQIGain` at a fixed period: ``u = step(reference, x)``.

    .. math::

        u_k = -K_x x_k - K_z z_k - K_{zz} w_k, \\qquad
        w_{k+1} = w_k + dt\\, z_k, \\qquad
        z_{k+1} = z_k + dt\\,(r_k - C_z x_k - D_z u_k)

    which is exactly the augmented model of :func:`augment_integral_discrete`
    (for a continuous design, a forward-Euler integrator at `dt`).

    Parameters
    ----------
    gain : LQIGain
    dt : float, s, optional
        Period; defaults to ``gain.dt`` (required for a continuous design).

    Attributes
    ----------
    z, w : ndarray, shape (nz,)
        Integral and double integral of the error (w stays 0 for ``order=1``).
    """

    def __init__(self, gain: LQIGain, *, dt: float | None = None):
        if dt is None:
            dt = gain.dt
        if dt is None:
            raise EstimatorError("LQIController: a continuous LQI gain needs dt (s), the controller period",
                                 name="dt")
        dt = _check_dt(dt, "LQIController")
        if gain.discrete and gain.dt is not None and abs(dt - gain.dt) > 1e-12 * gain.dt:
            raise EstimatorError(f"LQIController: dt = {dt} s differs from the design's {gain.dt} s", name="dt")
        self.gain, self.dt = gain, dt
        self.nz, self.n = gain.Cz.shape
        self.reset()

    def reset(self) -> None:
        """Integrators back to zero."""
        self.z = np.zeros(self.nz)
        self.w = np.zeros(self.nz)

    def step(self, reference, x) -> np.ndarray:
        """Control for state (estimate) ``x`` (shape (n,)) and ``reference`` (shape (nz,)); returns ``u`` (shape (m,))."""
        g = self.gain
        r = as_vector(reference, "reference", self.nz, owner="LQIController")
        x = as_vector(x, "x", self.n, owner="LQIController")
        u = -g.Kx @ x - g.Kz @ self.z
        if g.Kzz is not None:
            u = u - g.Kzz @ self.w
            self.w = self.w + self.dt * self.z
        self.z = self.z + self.dt * (r - g.Cz @ x - g.Dz @ u)
        return u
