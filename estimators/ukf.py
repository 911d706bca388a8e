"""Unscented Kalman filter: Julier or scaled sigma points, Python or bond-graph models.

:class:`UnscentedKalmanFilter` runs the UKF of [1]_ (Section III-A, eqs.
(13)-(24); the equations are in :mod:`estimators.ukf_engine`) with an injected
sigma-point scheme (:mod:`estimators.sigma_points`: the paper's
:class:`~estimators.sigma_points.JulierSigmaPoints` with :math:`\\kappa = 0`,
or :class:`~estimators.sigma_points.MerweScaledSigmaPoints`).  Its models are

* batched Python callables ``fx(X, u) -> X_new`` and ``hx(X, u) -> Y`` on all
  sigma points at once (``X`` of shape ``(2n+1, n)``); or
* a bond-graph model (:meth:`UnscentedKalmanFilter.from_model`): the discrete
  process model is one sample ``dt`` of the model's fixed-step RK4 with the
  input held, every sigma point in one batched call, the measurement model is
  a set of the model's outputs (held variables: :mod:`estimators.ukf_model`).

Engines
-------
``kernel="c"`` (model-based filters): one generated C function does the whole
step (Cholesky, sigma points, batched RK4 through the model's generated row
kernels, unscented transform, gain by Cholesky solves) on a preallocated
workspace (:mod:`estimators.ukf_c`).  ``kernel="numpy"``: the readable
reference (:mod:`estimators.ukf_engine`).  Both agree to rounding.

Positive definiteness
---------------------
No jitter is added.  ``P0`` and ``R`` must be positive definite and ``Q``
positive semidefinite (checked at construction, with every problem listed).
Covariances are kept exactly symmetric.  If a covariance loses positive
definiteness during the run (its Cholesky factorisation fails: ``P`` when
drawing sigma points, ``P_prior`` when redrawing them, ``S`` for the gain), an
:class:`~bondgraph.errors.EstimatorError` names the matrix, the step and the
time; non-finite model results are reported the same way.  No NaN is
propagated silently.

References
----------
.. [1] T. Shin, T. Ibayashi, K. Kogiso, "Detailed dynamic model of antagonistic
   PAM system and its experimental validation", seed 000 (``docs/references.md``).
"""
from __future__ import annotations

import numpy as np

from bondgraph.numerics.progress import Progress
from estimators.errors import EstimatorError

from .ukf_checks import check_covariance, check_vector, raise_problems, validate_setup
from .ukf_engine import NumpyEngine
from .ukf_model import ModelFunctions, StateMap, substeps_for
from .ukf_result import UKFResult

__all__ = ["UnscentedKalmanFilter", "UKFResult", "KERNELS"]

#: Accepted values of ``kernel``.
KERNELS = ("auto", "c", "numpy")


class UnscentedKalmanFilter:
    """Unscented Kalman filter with batched process and measurement models.

    Parameters
    ----------
    fx : callable (X, u) -> ndarray, shape (N, n)
        Discrete process model on all sigma points ``X`` (N, n) at once,
        over one sample with input ``u`` (whatever :meth:`predict` gets).
    hx : callable (X, u) -> ndarray, shape (N, m)
        Measurement model on all sigma points.
    x0 : array_like, shape (n,)
        Initial estimate :math:`\\hat x(0)`.
    P0 : array_like, shape (n, n)
        Initial covariance :math:`P(0)`, symmetric positive definite.
    Q : array_like, shape (n, n)
        Process noise covariance, symmetric positive semidefinite.
    R : array_like, shape (m, m)
        Measurement noise covariance, symmetric positive definite; sets m.
    points : SigmaPoints
        :class:`~estimators.sigma_points.JulierSigmaPoints` (the paper:
        ``kappa=0``) or :class:`~estimators.sigma_points.MerweScaledSigmaPoints`.
    redraw : bool
        True (the paper, filterpy 2.0): redraw the sigma points from
        :math:`\\hat x^-, P^-` before the measurement transform; False
        (filterpy 1.4): use the propagated points.
    dt : float, s
        Sample time; only advances :attr:`t`.
    t0 : float, s
        Initial time.
    state_names, measurement_names : sequence of str, optional

    Raises
    ------
    EstimatorError
        Listing every bad argument (shape, symmetry, definiteness, finiteness).

    Examples
    --------
    A random walk observed directly (the UKF is then the Kalman filter):

    >>> from estimators import JulierSigmaPoints
    >>> ukf = UnscentedKalmanFilter(fx=lambda X, u: X, hx=lambda X, u: X, x0=[0.0],
    ...                             P0=[[1.0]], Q=[[0.0]], R=[[1.0]],
    ...                             points=JulierSigmaPoints(1, kappa=2.0))
    >>> ukf.step(None, [2.0])
    >>> ukf.x, ukf.P
    (array([1.]), array([[0.5]]))
    """

    def __init__(self, *, fx, hx, x0, P0, Q, R, points, redraw=True, dt=0.0, t0=0.0,
                 state_names=None, measurement_names=None):
        if not (callable(fx) and callable(hx)):
            raise EstimatorError("fx and hx must be callables (X, u) -> array", "fx" if not callable(fx) else "hx")
        n = np.size(x0)
        m = np.shape(R)[0] if np.ndim(R) == 2 else None   # None: R is reported as not a matrix
        x0, P0, Q, R = validate_setup(points, x0, P0, Q, R, n, m, state_names or (), measurement_names or ())

        def propagate(X, u, t, d):
            return fx(X, u), d

        def measure(X, u, t, d):
            return hx(X, u)

        self._setup(NumpyEngine(propagate, measure, points, redraw, x0, P0, Q, R, t0, dt, np.zeros(0)),
                    points, redraw, state_names or tuple(f"x{i}" for i in range(n)), (),
                    measurement_names or tuple(f"y{i}" for i in range(m)), None)

    @classmethod
    def from_model(cls, model, *, dt, outputs, x0, P0, Q, R, points, redraw=True, state_map=None,
                   substeps=None, params=None, t0=0.0, d0=None, kernel="auto", backend="auto"):
        """A UKF whose process and measurement models are a bond-graph model.

        Parameters
        ----------
        model : BondGraph, StateEquations or CompiledModel
            The model (compiled with :func:`~bondgraph.numerics.evaluate.compile_model`
            and `backend` unless already compiled).
        dt : float, s
            Sample time: the process model is one sample of fixed-step RK4,
            input held (``substeps`` classic sub-steps).
        outputs : sequence of str
            Measured model outputs, in measurement order (SI / the model's units).
        x0, P0, Q, R : array_like
            As for the class, in the filter's coordinates (`state_map`).
        points : SigmaPoints
        redraw : bool
            See the class.
        state_map : StateMap, optional
            Filter coordinates :math:`x_f` with :math:`x_{model} = T x_f`; default
            the model's states.
        substeps : int, optional
            RK4 sub-steps per sample; default the fewest with a sub-step no
            longer than the model's ``fixed_step`` (``pam``: 4 for 1 ms).
        params : None, dict or array_like
            Model parameters (default the model's values).
        t0 : float, s
            Initial time.
        d0 : array_like, shape (n_held,), optional
            Initial held values; default the model's ``held_initial``.
        kernel : {"auto", "c", "numpy"}
            Engine; ``"auto"`` is ``"c"`` when a C compiler is available and
            the model has no algebraic unknowns.
        backend : {"auto", "c", "numpy"}
            Backend of :func:`~bondgraph.numerics.evaluate.compile_model` for the numpy engine.

        Returns
        -------
        UnscentedKalmanFilter

        Raises
        ------
        EstimatorError
            Bad arguments (all listed), or ``kernel="c"`` impossible.
        UnknownNameError
            An unknown output name.
        """
        from bondgraph.numerics.evaluate import CompiledModel, compile_model

        from .ukf_c import CEngine, c_engine_available

        if kernel not in KERNELS:
            raise EstimatorError(f"kernel must be one of {', '.join(map(repr, KERNELS))}; found {kernel!r}", "kernel")
        if not isinstance(model, CompiledModel):
            model = compile_model(model, backend=backend)
        if state_map is not None and not isinstance(state_map, StateMap):
            raise EstimatorError(f"state_map must be a StateMap; found {type(state_map).__name__}", "state_map")
        if not (np.isfinite(dt) and dt > 0):
            raise EstimatorError(f"dt must be a finite number of seconds > 0; found {dt!r}", "dt")
        eqs = model.equations
        fn = ModelFunctions(model, dt=dt, substeps=substeps_for(eqs, dt, substeps), outputs=outputs,
                            state_map=state_map, params=params)
        names = state_map.names if state_map else model.state_names
        units = state_map.units if state_map else tuple(eqs.units.get(s, "") for s in names)
        x0, P0, Q, R = validate_setup(points, x0, P0, Q, R, len(names), len(fn.outputs), names, fn.outputs)
        problems = []
        d0 = model.default_held if d0 is None else d0
        d0 = check_vector("d0", d0, len(model.held_names), problems, names=model.held_names)
        raise_problems(problems, f"UKF on model {eqs.name!r}")
        if kernel == "auto":
            kernel = "numpy" if c_engine_available(model) else "c"
        if kernel == "c":
            engine = CEngine(fn, points, redraw, x0, P0, Q, R, t0, d0)
        else:
            engine = NumpyEngine(fn.propagate, fn.measure, points, redraw, x0, P0, Q, R, t0, dt, d0,
                                 np.array(model.default_inputs))
        self = cls.__new__(cls)
        self._setup(engine, points, redraw, names, units, fn.outputs, model)
        return self

    def _setup(self, engine, points, redraw, state_names, units, measurement_names, model):
        self._e = engine
        self.points = points
        self.redraw = bool(redraw)
        self.state_names = tuple(state_names)
        self.units = tuple(units) or ("",) * len(self.state_names)
        self.measurement_names = tuple(measurement_names)
        self.model = model
        self.dim_x, self.dim_z = len(self.state_names), len(self.measurement_names)
        self._nu = len(model.input_names) if model is not None else None

    def __repr__(self):
        return (f"<UnscentedKalmanFilter {type(self.points).__name__} n={self.dim_x} m={self.dim_z} "
                f"redraw={self.redraw} kernel={self.kernel!r} step={self.k}>")

    # -- state ------------------------------------------------------------------------------
    kernel = property(lambda self: self._e.kind, doc='Engine in use, ``"c"`` or ``"numpy"``.')
    x_prior = property(lambda self: np.array(self._e.x_prior), doc="Prior mean :math:`\\hat x^-`, shape (n,).")
    P_prior = property(lambda self: np.array(self._e.P_prior), doc="Prior covariance :math:`P^-`, shape (n, n).")
    K = property(lambda self: np.array(self._e.K), doc="Last gain, shape (n, m).")
    S = property(lambda self: np.array(self._e.S), doc="Last innovation covariance, shape (m, m).")
    y_pred = property(lambda self: np.array(self._e.y_pred), doc="Last predicted measurement, shape (m,).")
    innovation = property(lambda self: np.array(self._e.innovation), doc="Last :math:`y - \\hat y`, shape (m,).")
    d = property(lambda self: np.array(self._e.d), doc="Held values of the model, shape (n_held,).")
    t = property(lambda self: self._e.t, doc="Filter time, s.")
    k = property(lambda self: self._e.k, doc="Number of predictions made.")

    @property
    def x(self) -> np.ndarray:
        """Current mean, shape (n,): the posterior after :meth:`update`, the prior after :meth:`predict`."""
        return np.array(self._e.x)

    @x.setter
    def x(self, value):
        problems = []
        v = check_vector("x", value, self.dim_x, problems, names=self.state_names)
        raise_problems(problems, "UKF state")
        self._e.set_state(x=v)

    @property
    def P(self) -> np.ndarray:
        """Current covariance, shape (n, n)."""
        return np.array(self._e.P)

    @P.setter
    def P(self, value):
        problems = []
        v = check_covariance("P", value, self.dim_x, problems, definite=True, names=self.state_names)
        raise_problems(problems, "UKF covariance")
        self._e.set_state(P=v)

    # -- steps ------------------------------------------------------------------------------
    def _checked(self, name, value, n, names, what):
        problems = []
        value = check_vector(name, value, n, problems, names=names)
        if problems:
            raise EstimatorError(f"UKF {what} at step {self.k}: {problems[0]}", name, step=self.k, time=self.t)
        return value

    def _check_u(self, u):
        return u if self._nu is None or u is None else self._checked("u", u, self._nu, self.model.input_names, "step")

    def _check_z(self, z):
        return self._checked("z", z, self.dim_z, self.measurement_names, "update")

    def predict(self, u=None) -> None:
        """Prediction, eqs. (13)-(18): :attr:`x`, :attr:`P` become the prior.

        Parameters
        ----------
        u : array_like, shape (n_inputs,), optional
            Input held over the sample (model-based: in the model's units; None
            -> the model's defaults at the first step, then the last input).

        Raises
        ------
        EstimatorError
            ``P`` not positive definite, or the model gives non-finite states.
        """
        self._e.predict(self._check_u(u))

    def update(self, z, u=None) -> None:
        """Measurement update, eqs. (19)-(24): :attr:`x`, :attr:`P` become the posterior.

        Parameters
        ----------
        z : array_like, shape (m,) or None
            Measurement; None skips the update (the prior stays).
        u : array_like, shape (n_inputs,), optional
            Input for the measurement model; default the one of the last :meth:`predict`.

        Raises
        ------
        EstimatorError
            `z` of the wrong shape or not finite (``name == "z"``), ``P_prior``
            or ``S`` not positive definite.
        """
        if z is None:
            return
        self._e.update(self._check_z(z), None if u is None else self._check_u(u))

    def step(self, u, z) -> None:
        """:meth:`predict` with `u`, then :meth:`update` with `z` (same input).

        Bad `u` or `z` raise before anything is done.
        """
        if z is not None and self._e.kind == "c":
            try:   # fast path: the kernel checks that u and z are finite
                if self._e.step(u, z) == 0:
                    return
            except (ValueError, TypeError):   # a wrong shape: named below
                pass
        z = None if z is None else self._check_z(z)
        self._e.predict(self._check_u(u))
        if z is not None:
            self._e.update(z, None)

    def batch_filter(self, z, u=None, *, times=None, progress=False) -> UKFResult:
        """Filter a recording: ``x[0]`` is the current state, then for k >= 1
        predict with ``u[k-1]`` and update with ``z[k]`` (the paper's recursion,
        :math:`\\hat x(k) = \\mathrm{UKF}(\\hat x(k-1), P(k-1), u(k-1), y(k))`).

        Parameters
        ----------
        z : array_like, shape (N, m)
            Measurements at the samples; ``z[0]`` is not used.
        u : array_like, shape (N, n_inputs), optional
            Inputs held from each sample to the next (``u[N-1]`` is not used);
            None: the model's defaults (or None for Python models).
        times : array_like, shape (N,), optional
            Sample times for the result; default ``t + k dt`` (``t + k`` if ``dt`` is 0).
        progress : bool
            Show the progress on stderr.

        Returns
        -------
        UKFResult

        Raises
        ------
        EstimatorError
            Wrong shapes, a non-finite measurement (named by row and column), or
            a failure at a step (named by step and matrix).
        """
        Z = np.asarray(z, dtype=float)
        if Z.ndim != 2 or Z.shape[1] != self.dim_z or Z.shape[0] < 1:
            raise EstimatorError(f"batch_filter: z must have shape (N, {self.dim_z}) "
                                 f"({', '.join(self.measurement_names)}); found {Z.shape}", "z")
        N = Z.shape[0]
        bad = np.argwhere(~np.isfinite(Z[1:]))
        if bad.size:
            r, c = bad[0]
            raise EstimatorError(f"batch_filter: z[{r + 1}, {c}] ({self.measurement_names[c]}) is not "
                                 f"finite; {len(bad)} non-finite value(s) in all", "z", step=int(r + 1))
        U = self._inputs(u, N)
        X, P = np.empty((N, self.dim_x)), np.empty((N, self.dim_x, self.dim_x))
        X[0], P[0] = self._e.x, self._e.P
        t_start = self.t
        bar = Progress(max(1, N), fmt="ukf: {percentage:5.1f} %  ({n}/{total} samples)", enabled=progress)
        if self._e.kind == "c" and N > 1:
            Zc = np.ascontiguousarray(Z[1:])
            for a in range(1, N, 2000):   # chunks, for the progress line
                b = min(N, a + 2000)
                self._e.run(U[a - 1:b - 1], Zc[a - 1:b - 1], X[a:b], P[a:b])
                bar.update_to(b)
        else:
            for k in range(1, N):
                self._e.predict(None if U is None else U[k - 1])
                self._e.update(Z[k], None)
                X[k], P[k] = self._e.x, self._e.P
                bar.update_to(k + 1)
        bar.close()
        if times is None:   # without a sample time (Python models, dt = 0): sample numbers
            times = t_start + (self._e.dt or 1.0) * np.arange(N)
        return UKFResult(times, X, P, self.state_names, self.units)

    def _inputs(self, u, N):
        if self._nu is None:
            return None if u is None else list(u)
        if u is None:
            return np.ascontiguousarray(np.tile(self.model.default_inputs, (N, 1)))
        U = np.asarray(u, dtype=float)
        if U.shape != (N, self._nu):
            raise EstimatorError(f"batch_filter: u must have shape ({N}, {self._nu}) "
                                 f"({', '.join(self.model.input_names)}); found {U.shape}", "u")
        bad = np.argwhere(~np.isfinite(U[:-1]))
        if bad.size:
            r, c = bad[0]
            raise EstimatorError(f"batch_filter: u[{r}, {c}] ({self.model.input_names[c]}) is not finite",
                                 "u", step=int(r))
        return np.ascontiguousarray(U)
