"""Linearised output response to extra inputs along a simulated trajectory.

Used by :mod:`diagnosis.graph_location` to estimate an unknown extra
effort/flow (or input correction) from the output residual.  Along the
nominal trajectory :math:`x_k, u_k` (states and held inputs at the sample
times :math:`t_k`) the model is linearised,

.. math::

    A_k = \\partial f/\\partial x, \\quad B_k = \\partial f/\\partial u, \\quad
    C_k = \\partial h/\\partial x, \\quad D_k = \\partial h/\\partial u,

and each sample interval :math:`h_k = t_{k+1} - t_k` is discretised with the
trapezoidal (Tustin) rule, A-stable for any step:

.. math::

    \\Phi_k = (I - A_k h_k/2)^{-1} (I + A_k h_k/2), \\quad
    \\Gamma_k = (I - A_k h_k/2)^{-1} B_k h_k,

so a perturbation :math:`\\delta u_k` of the inputs (held over the interval,
as the recording's inputs are) moves the outputs by

.. math::

    \\delta x_{k+1} = \\Phi_k \\delta x_k + \\Gamma_k \\delta u_k, \\quad
    \\delta y_k = C_k \\delta x_k + D_k \\delta u_k, \\quad \\delta x_0 = 0.

This is the first-order (Gauss-Newton) sensitivity of the simulation error
to the perturbation; it is exact for linear models up to the trapezoidal
discretisation.  Held variables (sampled friction) are taken at their
initial values in the Jacobians: the location only needs the direction of
the response, and every place is scored afterwards by a full simulation.
"""
from __future__ import annotations

import numpy as np

__all__ = ["LinearisedResponse"]


class LinearisedResponse:
    """Sensitivities of the outputs to chosen inputs along one simulated run.

    Parameters
    ----------
    compiled : bondgraph.evaluate.CompiledModel
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
        m = compiled
        self.t = run.t
        X, U, t = run.states, run.inputs, run.t
        self.input_names = tuple(inputs)
        self.output_names = tuple(outputs)
        ju = [m.input_index[n] for n in inputs]
        jy = [m.output_index[n] for n in outputs]
        n, nx = X.shape
        self.n_states = nx
        # B_k, D_k: central differences in each input (sources enter linearly: exact then)
        self.B = np.zeros((n, nx, len(ju)))
        self.D = np.zeros((n, len(jy), len(ju)))
        for c, j in enumerate(ju):
            delta = 1e-6 * max(1.0, float(np.max(np.abs(U[:, j]))))
            up, um = U.copy(), U.copy()
            up[:, j] += delta
            um[:, j] -= delta
            if nx:
                self.B[:, :, c] = (m.f(X, up, t=t, p=params) - m.f(X, um, t=t, p=params)) / (2 * delta)
            self.D[:, :, c] = (m.h(X, up, t=t, p=params)[:, jy] - m.h(X, um, t=t, p=params)[:, jy]) / (2 * delta)
        self.C = np.zeros((n, len(jy), nx))
        for j in range(nx):
            delta = 1e-6 * max(1.0, float(np.max(np.abs(X[:, j]))))
            xp, xm = X.copy(), X.copy()
            xp[:, j] += delta
            xm[:, j] -= delta
            self.C[:, :, j] = (m.h(xp, U, t=t, p=params)[:, jy] - m.h(xm, U, t=t, p=params)[:, jy]) / (2 * delta)
        self.Phi = np.zeros((max(n - 1, 0), nx, nx))
        self.Gamma = np.zeros((max(n - 1, 0), nx, len(ju)))
        if nx and n > 1:
            A = m.jac_x(X[:-1], U[:-1], t=t[:-1], p=params)
            h = np.diff(t)[:, None, None]
            eye = np.eye(nx)[None]
            left = eye - 0.5 * h * A
            self.Phi = np.linalg.solve(left, eye + 0.5 * h * A)
            self.Gamma = np.linalg.solve(left, self.B[:-1] * h)

    def response(self, channel, sequences, rows):
        """Output responses to perturbation sequences.

        Parameters
        ----------
        channel : ndarray of int, shape (m,)
            For each sequence, the index (in ``inputs``) of the input it perturbs.
        sequences : ndarray, shape (n, m)
            Perturbation of that input at each sample time (held over the interval).
        rows : ndarray of int, shape (n_rows,)
            Sample indices at which the responses are kept (increasing).

        Returns
        -------
        ndarray, shape (n_rows, n_outputs, m)
            :math:`\\delta y` at the kept samples, for each sequence.
        """
        channel = np.asarray(channel, dtype=int)
        seq = np.asarray(sequences, dtype=float)
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
