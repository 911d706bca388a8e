"""Linearised output response to extra inputs along a simulated trajectory.

Used by :mod:`diagnosis.graph_location` to estimate an unknown extra
effort/flow (or input correction) from the output residual.  Along the
nominal trajectory :math:`x_k, u_k` (states and held inputs at the sample
times :math:`t_k`) the model is linearised,

.. math::

    A_k = \\partial f/\\partial x, \\quad B_k = \\partial f/\\partial u, \\quad
    C_k = \\partial h/\\partial x, \\quad D_k = \\partial h/\\partial u,

(:math:`A_k` by central differences over a step of :math:`10^{-5}` of each
state's scale: a secant, finite where an orifice law's slope is infinite), and
each sample interval :math:`h_k = t_{k+1} - t_k` is discretised with the
trapezoidal (Tustin) rule, A-stable for any step, applied on
:math:`\\eta = h_k/2^s` and followed by s squarings
:math:`(\\Phi, \\Gamma) \\leftarrow (\\Phi^2, \\Phi\\Gamma + \\Gamma)` so that stiff
modes decay as in the simulation instead of ringing:

.. math::

    \\Phi = (I - A_k \\eta/2)^{-1} (I + A_k \\eta/2), \\quad
    \\Gamma = (I - A_k \\eta/2)^{-1} B_k \\eta,

so a perturbation :math:`\\delta u_k` of the inputs (held over the interval,
as the recording's inputs are) moves the outputs by

.. math::

    \\delta x_{k+1} = \\Phi_k \\delta x_k + \\Gamma_k \\delta u_k, \\quad
    \\delta y_k = C_k \\delta x_k + D_k \\delta u_k, \\quad \\delta x_0 = 0.

This is the first-order (Gauss-Newton) sensitivity of the simulation error
to the perturbation; it is exact for linear models up to the trapezoidal
discretisation.  Held variables (sampled friction) are re-evaluated by their
update law at each perturbed point (a held law is a function of the state
over a sub-step).  The location only needs the direction of the response;
every place is scored afterwards by a full simulation.
"""
from __future__ import annotations

import numpy as np

__all__ = ["LinearisedResponse"]


class LinearisedResponse:
    """Sensitivities of the outputs to chosen inputs along one simulated run.

    Parameters
    ----------
    compiled : bondgraph.numerics.evaluate.CompiledModel
        The model the run was made with.
    run : diagnosis.residuals.SimRun
        States and inputs at the sample times.
    params : ndarray, shape (n_params,)
        Parameter vector of the run.
    inputs : sequence of str
        Inputs whose perturbations are propagated.
    outputs : sequence of str
        Outputs whose responses are wanted.
    """

    def __init__(self, compiled, run, params, inputs, outputs):
        self._m, self._p = compiled, params
        self.t = t = run.t
        X, U = run.states, run.inputs
        self.input_names = tuple(inputs)
        self.output_names = tuple(outputs)
        ju = [compiled.input_index[n] for n in inputs]
        self._jy = [compiled.output_index[n] for n in outputs]
        n, nx = X.shape
        self.n_states = nx
        self.B = np.zeros((n, nx, len(ju)))
        self.D = np.zeros((n, len(self._jy), len(ju)))
        self.C = np.zeros((n, len(self._jy), nx))
        A = np.zeros((n, nx, nx))
        for c, j in enumerate(ju):
            self.B[:, :, c], self.D[:, :, c] = self._partials(X, U, t, U, j, 1e-6)
        for j in range(nx):
            # a secant over 1e-5 of the state's scale, not the analytic Jacobian: orifice laws
            # (sqrt of a pressure difference) have infinite slopes at zero flow
            A[:, :, j], self.C[:, :, j] = self._partials(X, U, t, X, j, 1e-5, states=True)
        self.Phi, self.Gamma = _discretise(A[:-1], self.B[:-1], np.diff(t))

    def _fh(self, x, u, t, held_at=None):
        """f and the chosen outputs h, with held variables re-evaluated at (x, `held_at` or u): a
        held law (Kikuuwe friction) is a function of the state over a sub-step, so its slope
        belongs in the linearisation (stiction acts as a very stiff damper there).  An input
        perturbation keeps the held law at the nominal inputs (`held_at`): a friction that sees
        an extra effort at its junction (the correction input) would switch between stick and
        slip within the difference step, and its slope there is the jump over the step."""
        m, p = self._m, self._p
        d = None
        if m.held_names:
            d = m.update_held(x, u if held_at is None else held_at, t=t, p=p,
                              step=float(m.equations.fixed_step or 0.0))
        f = m.f(x, u, t=t, p=p, d=d) if x.shape[1] else np.zeros((x.shape[0], 0))
        return f, m.h(x, u, t=t, p=p, d=d)[:, self._jy]

    def _partials(self, X, U, t, which, j, rel, states=False):
        scale = float(np.max(np.abs(which[:, j]))) if which.size else 0.0
        delta = rel * (scale if scale > 0 else 1.0)
        plus, minus = which.copy(), which.copy()
        plus[:, j] += delta
        minus[:, j] -= delta
        fp, hp = self._fh(plus, U, t) if states else self._fh(X, plus, t, held_at=U)
        fm, hm = self._fh(minus, U, t) if states else self._fh(X, minus, t, held_at=U)
        clean = lambda a: np.nan_to_num(a, nan=0.0, posinf=0.0, neginf=0.0)   # noqa: E731
        return clean((fp - fm) / (2 * delta)), clean((hp - hm) / (2 * delta))

    def response(self, channel, sequences, rows, columns=None):
        """Output responses to perturbation sequences.

        Parameters
        ----------
        channel : ndarray of int, shape (m,)
            For each sequence, the index (in ``inputs``) of the input it perturbs.
        sequences : ndarray, shape (n, m) or (n, m_base)
            Perturbation of that input at each sample time (held over the interval).
        rows : ndarray of int, shape (n_rows,)
            Sample indices at which the responses are kept (increasing).
        columns : ndarray of int, shape (m,), optional
            Sequence c is ``sequences[:, columns[c]]`` (a basis shared by several inputs is
            passed once); default ``0 .. m - 1``.

        Returns
        -------
        ndarray, shape (n_rows, n_outputs, m)
            :math:`\\delta y` at the kept samples, for each sequence.
        """
        from .errors import DiagnosisError
        from .graph_location_linear_c import propagate

        channel = np.asarray(channel, dtype=int)
        seq = np.asarray(sequences, dtype=float)
        columns = np.arange(seq.shape[1]) if columns is None else np.asarray(columns, dtype=int)
        rows = np.asarray(rows, dtype=int)
        n = seq.shape[0]
        if channel.shape != columns.shape:
            raise DiagnosisError(f"one channel per sequence: {channel.size} channels, {columns.size} sequences")
        if rows.size and (np.any(np.diff(rows) <= 0) or rows[0] < 0 or rows[-1] >= n):
            raise DiagnosisError(f"rows must be increasing sample indices below {n}")
        out = propagate(self.Phi, self.Gamma, self.C, self.D, channel, seq, columns, rows)
        return out if out is not None else self._response_numpy(channel, seq[:, columns], rows)

    def _response_numpy(self, channel, seq, rows):
        """:meth:`response`'s loop in numpy (no C compiler)."""
        n, m = seq.shape
        ny, nx = len(self.output_names), self.n_states
        out = np.empty((len(rows), ny, m))
        keep = np.zeros(n, dtype=bool)
        keep[rows] = True
        slot = np.cumsum(keep) - 1
        dx = np.zeros((nx, m))
        for k in range(n):
            if keep[k]:
                out[slot[k]] = self.C[k] @ dx + self.D[k][:, channel] * seq[k]
            if k < n - 1 and nx:
                dx = self.Phi[k] @ dx + self.Gamma[k][:, channel] * seq[k]
        return out


def _discretise(A, B, h, max_squarings: int = 20):
    """Held-input discretisation of each interval: Tustin on h / 2^s, then s squarings.

    ``(Phi, Gamma) <- (Phi Phi, Phi Gamma + Gamma)`` doubles the step; s is chosen
    so that :math:`h |A| / 2^s \\le 0.5`, so stiff modes (stiction, fast followers) decay
    as they do in the simulation instead of ringing as Tustin would at large
    :math:`h\\lambda`.
    """
    n, nx = A.shape[0], A.shape[1]
    eye = np.eye(nx)[None]
    if nx == 0 or n == 0:
        return np.zeros((n, nx, nx)), np.zeros((n, nx, B.shape[2]))
    norm = float(np.max(np.abs(A).sum(axis=2).max(axis=1) * h))
    s = int(np.clip(np.ceil(np.log2(max(norm / 0.5, 1.0))), 0, max_squarings))
    hs = (h / 2 ** s)[:, None, None]
    left = eye - 0.5 * hs * A
    singular = np.abs(np.linalg.det(left)) < 1e-12
    left[singular] = eye[0]
    Phi = np.linalg.solve(left, eye + 0.5 * hs * A)
    Gamma = np.linalg.solve(left, B * hs)
    for _ in range(s):
        Gamma = Phi @ Gamma + Gamma
        Phi = Phi @ Phi
    bad = ~(np.isfinite(Phi).all(axis=(1, 2)) & np.isfinite(Gamma).all(axis=(1, 2)))
    Phi[bad], Gamma[bad] = eye[0], 0.0
    return Phi, Gamma
