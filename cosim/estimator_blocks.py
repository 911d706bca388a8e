"""Estimators as co-simulation components: :class:`UKFBlock`.

A :class:`UKFBlock` wraps an :class:`~estimators.UnscentedKalmanFilter` built
on a bond-graph model (:meth:`~estimators.UnscentedKalmanFilter.from_model`)
so that it runs inside the master next to the plant FMU.  Its inputs are the
measured plant outputs (the filter's measurement vector) and the known plant
inputs; its outputs are the estimated states and, optionally, model outputs
evaluated at the estimate (e.g. the joint torque of the PAM joint, which is
not measured).

Timing
------
The paper's recursion ([1]_, Algorithm 1) is
:math:`\\hat x(k) = \\mathrm{UKF}(\\hat x(k-1), P(k-1), u(k-1), y(k))`.  In
the master, at each communication point :math:`t_k`:

* ``output(t_k)``, ``k >= 1``: one predict (with the plant input
  :math:`u(k-1)` held over the last step) and one update with the
  measurement :math:`y(k)` now on the inputs, in a single call of
  :meth:`~estimators.UnscentedKalmanFilter.step`; the outputs become
  :math:`\\hat x(k)`.  At ``t_0`` the outputs are the initial estimate
  :math:`\\hat x(0)` (no update), as in
  :meth:`~estimators.UnscentedKalmanFilter.batch_filter`;
* ``advance(t_k, dt)``: the plant input :math:`u(k)` now on the inputs is
  kept for the next prediction.

So the measurement inputs feed through to every output (a controller reads
:math:`\\hat x(k)` at :math:`t_k`), the plant-input ports do not (no
algebraic loop through the controller), and the block logs exactly what
``batch_filter(z, u)`` gives on the logged signals.

References
----------
.. [1] T. Shin, T. Ibayashi, K. Kogiso, "Detailed dynamic model of antagonistic
   PAM system and its experimental validation", seed 000 (``docs/references.md``).
"""
from __future__ import annotations

import numpy as np

from cosim.errors import CosimError, UnknownNameError
from estimators import UnscentedKalmanFilter

from .component import Port, PythonBlock

__all__ = ["UKFBlock"]


class UKFBlock(PythonBlock):
    """An unscented Kalman filter as a co-simulation component (module docstring: timing).

    Parameters
    ----------
    name : str
        Component name.
    ukf : UnscentedKalmanFilter
        A model-based filter (:meth:`UKFBlock.from_model` builds one); its
        ``dt`` must equal the master's communication step, its ``t`` the
        start time of the run.
    estimates : sequence of str, optional
        Model outputs to publish, evaluated at the estimate:
        :math:`\\hat y = h(T \\hat x, u)` (the mean's image, as the paper
        computes :math:`\\hat\\tau` from :math:`\\hat x`; not the unscented mean).
    state_map : StateMap, optional
        The state map the filter was built with (needed for `estimates`).
    params : None, dict or array_like, optional
        The model parameters the filter was built with (needed for `estimates`).

    Attributes
    ----------
    ukf : UnscentedKalmanFilter
        The wrapped filter (its ``x``, ``P``, ``k`` are the block's state).
    inputs : tuple of Port
        One per measured output, named and in the units of the model output
        (``P1``, ``P2`` in Pa for ``pam``), then one per model input
        (``u1``, ``u2`` in V).
    outputs : tuple of Port
        ``x_<state>`` per filter state in its unit (``x_psi`` rad, ``x_dpsi``
        rad/s, ``x_P1``, ``x_P2`` Pa with the paper's coordinates), then
        ``<output>_hat`` per entry of `estimates` in the model output's unit
        (``psi_hat`` deg, ``tau_hat`` N m).

    Raises
    ------
    CosimError
        The filter is not model-based, or `estimates` is given without the
        needed model.
    UnknownNameError
        An unknown model output in `estimates`.

    Examples
    --------
    >>> from plants.library import build
    >>> from estimators import JulierSigmaPoints
    >>> import numpy as np
    >>> block = UKFBlock.from_model("ukf", build("pam-locked"), dt=1e-3, outputs=("P1", "P2"),
    ...                             x0=[3e5, 3e5], P0=np.diag([1e6, 1e6]), Q=np.diag([1e6, 1e6]),
    ...                             R=np.diag([1e8, 1e8]), points=JulierSigmaPoints(2),
    ...                             estimates=("tau",))
    >>> [p.name for p in block.inputs], [p.name for p in block.outputs]
    (['P1', 'P2', 'u1', 'u2'], ['x_P_1', 'x_P_2', 'tau_hat'])
    """

    def __init__(self, name: str, ukf: UnscentedKalmanFilter, *, estimates=(), state_map=None,
                 params=None):
        if not isinstance(ukf, UnscentedKalmanFilter) or ukf.model is None:
            raise CosimError(f"block {name!r}: ukf must be an UnscentedKalmanFilter built on a model "
                             f"(UnscentedKalmanFilter.from_model); found {ukf!r}")
        model = ukf.model
        units = model.equations.units
        self.ukf = ukf
        self.estimates = tuple(estimates)
        for est in self.estimates:
            if est not in model.output_index:
                raise UnknownNameError("output", est, model.output_names, model.equations.name)
        self._est_index = [model.output_index[e] for e in self.estimates]
        self._state_map = state_map
        self._p = model.param_vector(params)
        self._nz, self._nu = ukf.dim_z, len(model.input_names)
        ins = [Port(m, units.get(m, ""), f"measured plant output {m}") for m in ukf.measurement_names]
        ins += [Port(u, units.get(u, ""), f"known plant input {u}, held over each step", start=v)
                for u, v in zip(model.input_names, model.default_inputs)]
        x0 = ukf.x
        outs = [Port(f"x_{s}", unit, f"UKF estimate of state {s}", start=float(x0[i]))
                for i, (s, unit) in enumerate(zip(ukf.state_names, ukf.units))]
        outs += [Port(f"{e}_hat", units.get(e, ""), f"model output {e} at the UKF estimate")
                 for e in self.estimates]
        super().__init__(name, inputs=ins, outputs=outs,
                         feedthrough=[(m.name, o.name) for m in ins[:self._nz] for o in outs])
        self._t0 = ukf.t
        self._dt = ukf._e.dt   # the sample time the filter was built with (no public attribute)
        self._u_held = None
        self._u_last = np.array(model.default_inputs)

    @classmethod
    def from_model(cls, name: str, model, *, estimates=(), **ukf_options) -> "UKFBlock":
        """Build the filter with :meth:`UnscentedKalmanFilter.from_model` and wrap it.

        Parameters
        ----------
        name : str
        model : BondGraph, StateEquations or CompiledModel
        estimates : sequence of str, optional
            As for the class.
        **ukf_options
            Keyword arguments of :meth:`UnscentedKalmanFilter.from_model`
            (``dt``, ``outputs``, ``x0``, ``P0``, ``Q``, ``R``, ``points``,
            ``state_map``, ``params``...); unknown ones raise ``TypeError``.

        Returns
        -------
        UKFBlock
        """
        ukf = UnscentedKalmanFilter.from_model(model, **ukf_options)
        return cls(name, ukf, estimates=estimates, state_map=ukf_options.get("state_map"),
                   params=ukf_options.get("params"))

    # -- component protocol -------------------------------------------------------------------
    def start(self, t0: float) -> None:
        """Check that the filter starts at ``t0`` (s) with its initial estimate."""
        if abs(t0 - self._t0) > 1e-9 * max(1.0, abs(t0)) or self.ukf.k:
            raise CosimError(f"block {self.name!r}: the UKF is at t = {self.ukf.t!r} s after "
                             f"{self.ukf.k} step(s); the run starts at t0 = {t0!r} s (build a new "
                             "block for each run, with the filter's t0 equal to the run's)")
        self._u_held = None
        self._u_last = np.array(self.ukf.model.default_inputs)

    def output(self, t: float) -> None:
        """At ``t_k``, k >= 1: predict with the held plant input, update with the measurement."""
        if self._u_held is not None:
            self.ukf.step(self._u_held, self.u[:self._nz])
            self._u_last, self._u_held = self._u_held, None
        x = self.ukf.x
        n = x.shape[0]
        self.y[:n] = x
        if self._est_index:
            self.y[n:] = self._model_outputs(x)

    def advance(self, t: float, dt: float) -> None:
        """Keep the plant input at ``t`` (V for ``pam``) for the prediction over ``[t, t + dt]``."""
        if abs(dt - self._dt) > 1e-9 * self._dt:
            raise CosimError(f"block {self.name!r}: the communication step {dt!r} s differs from "
                             f"the UKF's sample time dt = {self._dt!r} s")
        self._u_held = np.array(self.u[self._nz:])

    def _model_outputs(self, x) -> np.ndarray:
        xm = x if self._state_map is None else self._state_map.to_model(x)
        # the input of the last prediction: this step's plant input is not known yet at t_k
        return self.ukf.model.h(xm, self._u_last, p=self._p, d=self.ukf.d)[self._est_index]
