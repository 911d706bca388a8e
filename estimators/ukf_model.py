"""A bond-graph model as the UKF's process and measurement model.

:class:`ModelFunctions` turns a :class:`~bondgraph.numerics.evaluate.CompiledModel` into
the discrete process model of the filter: one sample :math:`\\Delta t` of the
model's fixed-step RK4 (``substeps`` classic sub-steps, inputs held), every
sigma point in one batched call, and the measurement model: named outputs of
the model.  :class:`StateMap` relates the filter's coordinates to the
model's when they differ (the paper's :math:`x = (\\psi, \\dot\\psi, P_1, P_2)`
against the ``pam`` model's ``(P_1, P_2, p_J, q_psi)``).

Held variables
--------------
A model with held variables (``pam``: the Kikuuwe friction torque ``T_f``)
carries them from sample to sample.  The filter keeps one set ``d`` of held
values.  At each prediction every sigma point starts the sample from ``d``;
the model replaces them at each sub-step start (``held_update``) along that
point's own trajectory; afterwards the filter's ``d`` becomes the held values
of the central sigma point (row 0, the posterior mean :math:`\\hat x`), i.e.
``d`` is advanced with the mean.  For ``pam`` the start value does not
matter (``T_f`` is recomputed from the state at every sub-step start).
The measurement model is evaluated with the filter's current ``d``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from estimators.errors import EstimatorError, UnknownNameError

__all__ = ["StateMap", "ModelFunctions", "substeps_for"]


@dataclass(frozen=True, eq=False)
class StateMap:
    """Linear map from the filter's state to the model's: :math:`x_{model} = T x_{filter}`.

    Parameters
    ----------
    matrix : array_like, shape (n_model_states, n_filter_states)
        :math:`T`; square and invertible (condition number below 1e12).
    names : sequence of str
        Names of the filter's states.
    units : sequence of str, optional
        Their units (for results and plots).

    Attributes
    ----------
    matrix, inverse : ndarray, read-only
        :math:`T` and :math:`T^{-1}`.

    Examples
    --------
    The paper's coordinates :math:`(\\psi, \\dot\\psi, P_1, P_2)` for the
    ``pam`` model's states ``(P_1, P_2, p_J, q_psi)``, with
    :math:`p_J = J \\dot\\psi`:

    >>> J = 4.263e-4
    >>> m = StateMap.scaled(("P_1", "P_2", "p_J", "q_psi"),
    ...                     {"psi": ("q_psi", 1.0), "dpsi": ("p_J", J),
    ...                      "P1": ("P_1", 1.0), "P2": ("P_2", 1.0)},
    ...                     units=("rad", "rad/s", "Pa", "Pa"))
    >>> m.names
    ('psi', 'dpsi', 'P1', 'P2')
    >>> m.to_model([0.1, 2.0, 3e5, 2e5]).tolist()
    [300000.0, 200000.0, 0.0008526, 0.1]
    """

    matrix: np.ndarray
    names: tuple
    units: tuple = ()
    inverse: np.ndarray = None

    def __post_init__(self):
        T = np.array(self.matrix, dtype=float)
        names = tuple(self.names)
        if T.ndim != 2 or T.shape[0] != T.shape[1] or T.shape[1] != len(names) or not np.isfinite(T).all():
            raise EstimatorError(f"state map: expected a finite square matrix with one column per "
                                 f"filter state ({len(names)}); found shape {T.shape}", "state_map")
        if np.linalg.cond(T) > 1e12:
            raise EstimatorError("state map: the matrix is singular (or nearly: condition number "
                                 f"{np.linalg.cond(T):.3g})", "state_map")
        Ti = np.linalg.inv(T)   # a fixed small matrix, applied to every sigma point
        T.flags.writeable = Ti.flags.writeable = False
        units = tuple(self.units) or ("",) * len(names)
        if len(units) != len(names):
            raise EstimatorError(f"state map: {len(units)} units for {len(names)} states", "state_map")
        object.__setattr__(self, "matrix", T)
        object.__setattr__(self, "inverse", Ti)
        object.__setattr__(self, "names", names)
        object.__setattr__(self, "units", units)

    @classmethod
    def scaled(cls, model_states, mapping, *, units=()) -> "StateMap":
        """A map in which each model state is a multiple of one filter state.

        Parameters
        ----------
        model_states : sequence of str
            The model's state names, in its order (``model.state_names``).
        mapping : dict filter_name -> (model_state, factor)
            ``model_state = factor * filter_state``; every model state exactly once.
        units : sequence of str, optional
            Units of the filter states, in `mapping` order.

        Returns
        -------
        StateMap
        """
        model_states = tuple(model_states)
        index = {nm: i for i, nm in enumerate(model_states)}
        T = np.zeros((len(model_states), len(mapping)))
        used = []
        for j, (fname, (mname, factor)) in enumerate(mapping.items()):
            if mname not in index:
                raise UnknownNameError("state", mname, model_states)
            T[index[mname], j] = float(factor)
            used.append(mname)
        missing = [nm for nm in model_states if nm not in used]
        twice = sorted({nm for nm in used if used.count(nm) > 1})
        if missing or twice:
            raise EstimatorError(f"state map: every model state must appear once; missing "
                                 f"{missing or 'none'}, repeated {twice or 'none'}", "state_map")
        return cls(T, tuple(mapping), tuple(units))

    def to_model(self, x) -> np.ndarray:
        """Model states of filter states `x` (shape (n,) or (N, n))."""
        return np.asarray(x, dtype=float) @ self.matrix.T

    def to_filter(self, x_model) -> np.ndarray:
        """Filter states of model states (shape (n,) or (N, n))."""
        return np.asarray(x_model, dtype=float) @ self.inverse.T


def substeps_for(eqs, dt: float, substeps: int | None) -> int:
    """Sub-steps per sample: `substeps`, else the fewest with a sub-step no longer than
    the model's ``fixed_step`` (1 for a smooth model), as :func:`~bondgraph.numerics.simulation.simulate`."""
    if substeps is not None:
        if int(substeps) != substeps or substeps < 1:
            raise EstimatorError(f"substeps must be an integer >= 1; found {substeps!r}", "substeps")
        return int(substeps)
    if not eqs.fixed_step:
        return 1
    return max(1, math.ceil(dt / eqs.fixed_step - 1e-9))


class ModelFunctions:
    """Process and measurement functions of a compiled model, batched over sigma points.

    Parameters
    ----------
    model : CompiledModel
    dt : float, s
        Sample time of the filter.
    substeps : int
        RK4 sub-steps per sample.
    outputs : sequence of str
        Names of the measured model outputs, in the order of the measurement vector.
    state_map : StateMap or None
        None: the filter's state is the model's.
    params : None, dict or array_like
        Model parameters (see :class:`~bondgraph.numerics.evaluate.CompiledModel`).

    Attributes
    ----------
    output_index : tuple of int
        Indices of `outputs` among the model's outputs.
    p : ndarray, shape (1, n_params)
    """

    def __init__(self, model, *, dt, substeps, outputs, state_map, params):
        self.model = model
        self.dt = float(dt)
        self.substeps = int(substeps)
        self.h = self.dt / self.substeps
        index = []
        for name in outputs:
            if name not in model.output_index:
                raise UnknownNameError("output", name, model.output_names, model.equations.name)
            index.append(model.output_index[name])
        self.outputs = tuple(outputs)
        self.output_index = tuple(index)
        self.state_map = state_map
        self.p = np.ascontiguousarray(model.param_vector(params))

    def propagate(self, X, u, t, d):
        """Sigma points `X` (N, n) after one sample from time `t` with input `u` held.

        Returns the new points (N, n) and the held values of row 0 (the
        central point, see the module docstring).
        """
        m = self.state_map
        Xm = X if m is None else X @ m.matrix.T
        Xm, D = self.model.rk4_step(Xm, u, t0=t, h=self.h, substeps=self.substeps, p=self.p,
                                    d=np.broadcast_to(d, (X.shape[0], d.size)))
        return (Xm if m is None else Xm @ m.inverse.T), D[0].copy()

    def measure(self, X, u, t, d):
        """Measured outputs (N, n_outputs) of sigma points `X` (N, n) at time `t`."""
        m = self.state_map
        Xm = X if m is None else X @ m.matrix.T
        Y = self.model.h(Xm, u, t=t, p=self.p, d=d)
        return Y[:, self.output_index]
