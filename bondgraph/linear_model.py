"""Linear time-invariant models with named signals: :class:`LinearModel`.

``LinearModel`` holds ``(A, B, C, D)`` of a linearisation (see
:mod:`bondgraph.linearization`) with the names and units of its states,
inputs and outputs, and turns them into poles, frequency responses, Bode
data and python-control systems.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Mapping

import numpy as np

from .errors import ArgumentError, ParameterError

__all__ = ["LinearModel", "EQUILIBRIUM_ATOL"]

EQUILIBRIUM_ATOL = 1e-9


# ---------------------------------------------------------------------------
# Result object
# ---------------------------------------------------------------------------
def _frozen_array(value, shape, what: str) -> np.ndarray:
    arr = np.array(value, dtype=float)
    if arr.shape != shape:
        if arr.size or math.prod(shape):  # JSON turns an empty (0, m) matrix into []
            raise ArgumentError(f"{what}: expected shape {shape} but found {arr.shape}")
        arr = arr.reshape(shape)
    arr.flags.writeable = False
    return arr


@dataclass(frozen=True, eq=False)
class LinearModel:
    """A linear state-space model about an operating point, with named signals.

    .. math::

        \\delta\\dot x = A\\,\\delta x + B\\,\\delta u + \\dot x_0, \\qquad
        \\delta y = C\\,\\delta x + D\\,\\delta u

    Attributes
    ----------
    name : str
        Name of the model the linearisation belongs to.
    A : ndarray, shape (n_states, n_states)
        :math:`\\partial \\dot x / \\partial x`, entry ``(i, j)`` in
        unit(x_i)/s per unit(x_j).
    B : ndarray, shape (n_states, n_inputs)
        :math:`\\partial \\dot x / \\partial u`.
    C : ndarray, shape (n_outputs, n_states)
        :math:`\\partial y / \\partial x`.
    D : ndarray, shape (n_outputs, n_inputs)
        :math:`\\partial y / \\partial u`.
    states, inputs, outputs : tuple of str
        Signal names, in the order of the matrix rows/columns.
    units : mapping str -> str
        Unit of every state, input, output, held and algebraic name.
    operating_point : mapping str -> float
        Values (SI) of the states, inputs, held variables and solved
        algebraic unknowns at which the model was linearised.
    t : float, s
        Time at which a time-varying model was frozen.
    params : mapping str -> float
        Parameter values used (SI).
    xdot : ndarray, shape (n_states,)
        :math:`\\dot x_0 = f` at the point (zero at an equilibrium).
    y : ndarray, shape (n_outputs,)
        :math:`y_0 = h` at the point.
    equilibrium_residual : float
        :math:`\\lVert \\dot x_0 \\rVert_2` (mixed SI units).
    equilibrium_atol : float
        Tolerance on `equilibrium_residual` used by :attr:`is_equilibrium`.
    derivatives : mapping str -> str
        How each state's and input's column was obtained: ``"symbolic"`` or
        ``"one-sided numerical (right, step ...)"`` (see
        :func:`bondgraph.linearization.linearize`).  Empty when not known.
    kinks : tuple of str
        Switches of the model on their switching surface at the point (where
        the symbolic derivative does not apply).
    """

    name: str
    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    states: tuple
    inputs: tuple
    outputs: tuple
    units: Mapping = field(default_factory=dict)
    operating_point: Mapping = field(default_factory=dict)
    t: float = 0.0
    params: Mapping = field(default_factory=dict)
    xdot: np.ndarray | None = None
    y: np.ndarray | None = None
    equilibrium_residual: float = 0.0
    equilibrium_atol: float = EQUILIBRIUM_ATOL
    derivatives: Mapping = field(default_factory=dict)
    kinks: tuple = ()

    def __post_init__(self):
        for name in ("states", "inputs", "outputs"):
            object.__setattr__(self, name, tuple(str(s) for s in getattr(self, name)))
        n, m, p = len(self.states), len(self.inputs), len(self.outputs)
        shapes = {"A": (n, n), "B": (n, m), "C": (p, n), "D": (p, m), "xdot": (n,), "y": (p,)}
        for attr, shape in shapes.items():
            value = getattr(self, attr)
            value = np.zeros(shape) if value is None else value
            object.__setattr__(self, attr, _frozen_array(value, shape, f"LinearModel {self.name!r}: {attr}"))
        object.__setattr__(self, "kinks", tuple(str(k) for k in self.kinks))
        for attr in ("units", "operating_point", "params", "derivatives"):
            object.__setattr__(self, attr, MappingProxyType(dict(getattr(self, attr) or {})))
        object.__setattr__(self, "t", float(self.t))
        object.__setattr__(self, "equilibrium_residual", float(self.equilibrium_residual))

    # -- point -------------------------------------------------------------
    @property
    def is_equilibrium(self) -> bool:
        """True when ``equilibrium_residual <= equilibrium_atol``."""
        return self.equilibrium_residual <= self.equilibrium_atol

    @property
    def x0(self) -> np.ndarray:
        """State at the operating point, shape (n_states,)."""
        return np.array([self.operating_point[s] for s in self.states], dtype=float)

    @property
    def u0(self) -> np.ndarray:
        """Input at the operating point, shape (n_inputs,)."""
        return np.array([self.operating_point[s] for s in self.inputs], dtype=float)

    def poles(self) -> np.ndarray:
        """Eigenvalues of `A`, rad/s, complex ndarray of shape (n_states,), sorted by real then imaginary part."""
        if not self.states:
            return np.zeros(0, dtype=complex)
        return np.sort_complex(np.linalg.eigvals(self.A))

    # -- frequency domain --------------------------------------------------
    def _index(self, kind: str, name: str) -> int:
        names = self.inputs if kind == "input" else self.outputs
        if name not in names:
            raise ParameterError(
                f"unknown {kind} {name!r} of {self.name!r}; expected one of {', '.join(names) or '(none)'}",
                name=str(name))
        return names.index(name)

    def frequency_response(self, input: str, output: str, omega) -> np.ndarray:
        """Complex frequency response from one input to one output.

        .. math:: G(j\\omega) = C_i\\,(j\\omega I - A)^{-1} B_j + D_{ij}

        evaluated with a linear solve per frequency (no inverse).

        Parameters
        ----------
        input, output : str
            Signal names.
        omega : array_like, shape (n_freq,), rad/s
            Angular frequencies.

        Returns
        -------
        ndarray of complex, shape (n_freq,)
            In unit(output)/unit(input).

        Raises
        ------
        ParameterError
            Unknown signal name, non-finite `omega`, or a frequency that hits
            an eigenvalue of `A` on the imaginary axis.
        """
        j, i = self._index("input", input), self._index("output", output)
        w = np.asarray(omega, dtype=float)
        if w.ndim != 1 or not np.all(np.isfinite(w)):
            raise ParameterError(f"omega must be a 1-D array of finite angular frequencies (rad/s), "
                                 f"got shape {w.shape}", name="omega")
        n = len(self.states)
        if n == 0:
            return np.full(w.shape, complex(self.D[i, j]))
        # (j w I - A) X = B_j for every frequency at once: a stack of solves.
        lhs = 1j * w[:, None, None] * np.eye(n) - self.A
        rhs = np.broadcast_to(self.B[:, j].astype(complex), (w.size, n))[..., None]
        try:
            x = np.linalg.solve(lhs, rhs)[..., 0]
        except np.linalg.LinAlgError:
            raise ParameterError(
                f"omega hits a pole of {self.name!r} on the imaginary axis (poles: "
                f"{', '.join(f'{p:.6g}' for p in self.poles())}); leave that frequency out",
                name="omega") from None
        return x @ self.C[i] + self.D[i, j]

    def bode(self, input: str, output: str, omega=None):
        """Bode data from one input to one output.

        Parameters
        ----------
        input, output : str
            Signal names.
        omega : array_like, shape (n_freq,), rad/s, optional
            Angular frequencies; by default 2 decades below the slowest
            to 2 decades above the fastest non-zero pole, log-spaced.

        Returns
        -------
        omega : ndarray, shape (n_freq,), rad/s
        magnitude : ndarray, shape (n_freq,)
            :math:`|G(j\\omega)|`, unit(output)/unit(input) (not dB).
        phase : ndarray, shape (n_freq,), deg
            :math:`\\arg G(j\\omega)`, unwrapped along `omega`.
        """
        w = self._default_omega() if omega is None else np.asarray(omega, dtype=float)
        g = self.frequency_response(input, output, w)
        return w, np.abs(g), np.degrees(np.unwrap(np.angle(g)))

    def _default_omega(self) -> np.ndarray:
        mags = np.abs(self.poles())
        mags = mags[mags > 1e-12 * max(1.0, mags.max(initial=0.0))]
        lo, hi = (mags.min(), mags.max()) if mags.size else (1.0, 1.0)
        lo_dec, hi_dec = math.floor(math.log10(lo)) - 2, math.ceil(math.log10(hi)) + 2
        return np.logspace(lo_dec, hi_dec, 50 * (hi_dec - lo_dec) + 1)

    # -- python-control ----------------------------------------------------
    def to_control(self):
        """This model as a python-control ``StateSpace`` with named states, inputs and outputs."""
        import control  # heavy import (pyplot); only when asked for

        return control.ss(self.A, self.B, self.C, self.D, states=list(self.states),
                          inputs=list(self.inputs), outputs=list(self.outputs), name=self.name)

    def transfer_function(self, input: str, output: str):
        """Transfer function from one input to one output (python-control ``TransferFunction``).

        .. math:: G(s) = C_i\\,(s I - A)^{-1} B_j + D_{ij}

        Uncancelled pole-zero pairs (uncontrollable/unobservable modes) are
        kept; call ``.minreal()`` on the result to remove them.
        """
        import control

        j, i = self._index("input", input), self._index("output", output)
        siso = control.ss(self.A, self.B[:, [j]], self.C[[i], :], self.D[[i]][:, [j]],
                          inputs=[input], outputs=[output], name=f"{self.name}:{input}->{output}")
        return control.ss2tf(siso, name=f"{self.name}:{input}->{output}")

    # -- I/O ---------------------------------------------------------------
    def to_dict(self) -> dict:
        """JSON-friendly dict (lists and floats); :meth:`from_dict` reads it back."""
        return {
            "name": self.name,
            "states": list(self.states), "inputs": list(self.inputs), "outputs": list(self.outputs),
            "A": self.A.tolist(), "B": self.B.tolist(), "C": self.C.tolist(), "D": self.D.tolist(),
            "units": dict(self.units),
            "operating_point": {k: float(v) for k, v in self.operating_point.items()},
            "t": self.t,
            "params": {k: float(v) for k, v in self.params.items()},
            "xdot": self.xdot.tolist(), "y": self.y.tolist(),
            "equilibrium_residual": self.equilibrium_residual,
            "equilibrium_atol": self.equilibrium_atol,
            "derivatives": dict(self.derivatives),
            "kinks": list(self.kinks),
        }

    @classmethod
    def from_dict(cls, data: Mapping) -> "LinearModel":
        """The model :meth:`to_dict` wrote (missing optional keys take their defaults)."""
        required = ("name", "states", "inputs", "outputs", "A", "B", "C", "D")
        missing = [k for k in required if k not in data]
        if missing:
            raise ParameterError(f"LinearModel dict lacks key(s) {', '.join(missing)}; "
                                 f"expected at least {', '.join(required)}", name=missing[0])
        known = set(cls.__dataclass_fields__)
        unknown = sorted(set(data) - known)
        if unknown:
            raise ParameterError(f"LinearModel dict has unknown key(s) {', '.join(unknown)}; "
                                 f"expected keys among {', '.join(sorted(known))}", name=unknown[0])
        return cls(**dict(data))

    def __str__(self) -> str:
        unit = lambda k: f" {self.units[k]}" if self.units.get(k) else ""  # noqa: E731
        point = ", ".join(f"{k} = {v:.6g}{unit(k)}" for k, v in self.operating_point.items())
        status = ("equilibrium" if self.is_equilibrium else "NOT an equilibrium")
        lines = [
            f"LinearModel {self.name!r}: " + ", ".join(
                f"{len(names)} {what}{'' if len(names) == 1 else 's'}" for what, names in
                (("state", self.states), ("input", self.inputs), ("output", self.outputs))),
            f"operating point (t = {self.t:.6g} s): {point or '(none)'}",
            f"{status}: |dx/dt| = {self.equilibrium_residual:.3g}"
            + ("" if self.is_equilibrium else
               " (" + ", ".join(f"d{s}/dt = {v:.6g}" for s, v in zip(self.states, self.xdot)) + ")"),
        ]
        numeric = [k for k, v in self.derivatives.items() if v != "symbolic"]
        if numeric:
            lines.append("derivatives: symbolic, except one-sided numerical (right) by " + ", ".join(numeric))
        for label, mat, rows, cols in (("A = d(dx/dt)/dx", self.A, self.states, self.states),
                                       ("B = d(dx/dt)/du", self.B, self.states, self.inputs),
                                       ("C = dy/dx", self.C, self.outputs, self.states),
                                       ("D = dy/du", self.D, self.outputs, self.inputs)):
            lines.append(label)
            lines.extend(_format_matrix(mat, rows, cols))
        return "\n".join(lines)


def _format_matrix(mat: np.ndarray, rows, cols) -> list[str]:
    if mat.size == 0:
        return ["  (empty)"]
    cells = [[f"{v:.6g}" for v in row] for row in mat]
    width = max([len(c) for c in cols] + [len(c) for row in cells for c in row])
    first = max(len(r) for r in rows)
    out = ["  " + " " * first + "".join(f"  {c:>{width}}" for c in cols)]
    for r, row in zip(rows, cells):
        out.append(f"  {r:<{first}}" + "".join(f"  {c:>{width}}" for c in row))
    return out


# ---------------------------------------------------------------------------
