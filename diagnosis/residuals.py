"""Nominal simulation on recorded inputs, residuals, noise level and NRMSE.

:class:`OutputSimulator` compiles a model once and simulates it on an
experiment's time grid as often as a fit needs: recorded inputs are
zero-order held over each sample interval (as a co-simulation master holds
them), and each interval is integrated by the compiled classic RK4 of
:mod:`bondgraph.numerics.evaluate` (``rk4_step``) in equal sub-steps no longer than

* the model's ``fixed_step`` (held variables such as Kikuuwe friction), and
* for smooth models :math:`0.5 / \\lambda_{max}`, with :math:`\\lambda_{max}`
  the largest eigenvalue modulus of :math:`\\partial f/\\partial x` at the
  initial point (RK4 stays accurate for :math:`h|\\lambda| \\le 0.5`).

A smooth model that would need more such sub-steps per sample than the L-stable linearly
implicit Rosenbrock W-method ROS34PW2 of :mod:`bondgraph.numerics.evaluate_stiff` costs (at
most ``_STIFF_SUBSTEPS``, 1000; fewer the more its derivative costs) runs on that instead.

This is the fixed-step scheme of :func:`bondgraph.numerics.simulate` with the sample
intervals of the recording as output intervals, uneven sampling included;
unlike ``simulate`` it does not restart an adaptive solver at every table
breakpoint, so a 1 kHz recording costs one compiled call per sample.

NRMSE (the package's shared definition): :math:`\\mathrm{rms}(y - \\hat y) /
\\mathrm{std}(y)`.
"""
from __future__ import annotations

import copy
import numbers
from dataclasses import dataclass

import numpy as np
import sympy as sp

from .errors import BondcosimError, DiagnosisError

__all__ = ["OutputSimulator", "SimRun", "input_matrix", "settle_substeps", "simulate_outputs", "nrmse",
           "noise_sigma", "Residuals", "residuals"]

_RK4_ACCURACY = 0.5       # h * |lambda_max| per sub-step for smooth models
#: h |lambda_max| per sub-step of a model with held variables: RK4's stability (2.78 on the negative
#: real axis) with a margin.  Their stiff modes are a sharp friction's relaxation under a held law,
#: which must not chatter; resolving them to :data:`_RK4_ACCURACY` made the pam's friction cases
#: 5-7 times slower (seed 2727, cases 010 and 024, on a loaded machine) for the same accuracy (at seed
#: 3535 case 019's truth values the model is 3.8 noise sigmas of tau off that truth with either)
_HELD_RK4_REACH = 2.0
#: Most RK4 sub-steps per sample interval of any run.  A smooth model past them, or sooner where
#: its derivative costs more (:meth:`OutputSimulator._stiff_from`), is integrated by the linearly
#: implicit Rosenbrock method instead (:mod:`bondgraph.numerics.evaluate_stiff`); a model with held
#: variables has no such path and fails.  Both paths agree to 0.01 noise sigmas on the exoskeleton
#: and to 1e-5 of tau's span on the pam-frictionless.
_STIFF_SUBSTEPS = 1000
#: states along a run gone to infinity whose Jacobian checks its RK4 sub-step
#: (:meth:`OutputSimulator._step_along`), the share of its sub-step below which it is simulated
#: again with the one they need, and how many times at most
_ALONG, _RESTEP, _RESTEPS = 24, 0.5, 2
#: h |lambda| past which classic RK4 is unstable (2.79 on the negative real axis, 2.83 on the imaginary one)
_RK4_STABLE = 2.78
#: The cost model that sets where (session 22, measured here): the stiff path costs about 100 us
#: per sample interval, mostly in Python (the Jacobian, its eigenvalues, W^-1), and an RK4 sub-step
#: 47 ns plus 0.4 ns per operation of the state derivatives (sympy ``count_ops``): the
#: exoskeleton's (64 operations) 73 ns, the pam-frictionless's (1512) 650 ns.  So the crossover is
#: at about 150 sub-steps on the pam-frictionless, where one run took 0.8 s on RK4 at 118
#: sub-steps and 1.1 s on the stiff path, and beyond 1000 on the exoskeleton, whose nominal took
#: 0.1-0.2 s on RK4 at 515 sub-steps and 0.3-0.5 s on the stiff path (with a fixed 150 its
#: diagnoses took 2-3 times as long; with 1000 a pam-frictionless case took 682 s for 66 s).
_STIFF_INTERVAL_COST = 100e-6
_RK4_STEP_COST = (47e-9, 0.4e-9)


#: RK4 runs of one batch share the smallest sub-step of their group; a run whose own sub-step is more
#: than this many times longer than a group's smallest is run in a group of its own (_alike_steps)
_STEP_SPREAD = 4.0


def _alike_steps(rows, h) -> list:
    """`rows` (indices into the sub-steps `h`) in groups whose longest sub-step is at most
    :data:`_STEP_SPREAD` times their shortest, longest first.  A finite-difference Jacobian's runs
    need nearly the same sub-step and must share one (a difference across two discretisations is
    their error, not the parameter's effect), while a fit's starts may hold a sharp friction fifty
    times the guess's level: on the pam (held variables, no Rosenbrock path) its 744 RK4 sub-steps
    per sample were imposed on the guess and two other starts that need 4, and that one batch took
    16.6 of the fit's 17.8 s (seed 4848, case 034)."""
    order = rows[np.argsort(-h[rows], kind="stable")]
    groups, first = [], 0
    for k in range(1, order.size + 1):
        if k == order.size or h[order[k]] * _STEP_SPREAD < h[order[first]]:
            groups.append(np.sort(order[first:k]))
            first = k
    return groups


@dataclass
class SimRun:
    """One simulation on an experiment's grid (SI units).

    Attributes
    ----------
    t : ndarray, shape (n,)
        Times, s.
    states : ndarray, shape (n, n_states)
    inputs : ndarray, shape (n, n_inputs)
        Inputs held over each interval from its start.
    outputs : dict str -> ndarray, shape (n,)
    state_names, input_names : tuple of str
    substeps : int
        Most sub-steps of a sample interval (RK4, or the Rosenbrock method for a stiff smooth model).
    """

    t: np.ndarray
    states: np.ndarray
    inputs: np.ndarray
    outputs: dict
    state_names: tuple
    input_names: tuple
    substeps: int


def input_matrix(eqs, t, inputs: dict, params: dict | None = None, *, past=None) -> np.ndarray:
    """Input values at times `t`, shape (n, n_inputs), in the model's input order.

    Parameters
    ----------
    eqs : StateEquations
    t : ndarray, shape (n,)
        Times, s.
    inputs : dict str -> ndarray, shape (n,)
        Recorded inputs by name; others take ``input_functions`` (of ``t``) or
        ``input_defaults``.
    params : dict str -> float, optional
        Parameter values for the delays of delayed inputs and their values before the record
        (``eqs.input_delays``, filled from their sources: :mod:`bondgraph.numerics.input_delays`);
        default the model's.
    past : tuple (t, U), optional
        The inputs recorded before `t` (times, s, and the matrix in model input order), which the
        delayed inputs read while their delay reaches back before ``t[0]``.

    Raises
    ------
    UnknownNameError
        An input name the model does not have.
    DiagnosisError
        A recorded value given for a delayed input (its source is what is recorded).
    """
    from bondgraph.numerics.input_delays import before_values, delay_values, inputs_on_grid
    from diagnosis.errors import UnknownNameError

    for name in inputs:
        if name not in eqs.input_names:
            raise UnknownNameError("input", name, eqs.input_names, eqs.name)
        if name in eqs.input_delays:
            raise DiagnosisError(f"input {name!r} of model {eqs.name!r} is input "
                                 f"{eqs.input_delays[name].source!r} delayed: give that one's record")
    U = _undelayed_matrix(eqs, t, inputs)
    _, U_grid, at = inputs_on_grid(eqs, t, U, delay_values(eqs, params), before_values(eqs, params), past=past)
    return np.ascontiguousarray(U_grid[at])


def _past_inputs(eqs, experiment):
    """``(t, U)`` of the inputs recorded before `experiment` (:attr:`Experiment.history
    <diagnosis.recording.Experiment.history>`, model input order), which its delayed inputs read;
    None without delayed inputs or history."""
    history = getattr(experiment, "history", None)
    if not eqs.input_delays or history is None or not history.t.size:
        return None
    t = np.asarray(history.t, dtype=float)
    return t, _undelayed_matrix(eqs, t, {k: v for k, v in history.inputs.items() if k in eqs.input_names})


def _undelayed_matrix(eqs, t, inputs: dict) -> np.ndarray:
    U = np.empty((t.size, len(eqs.input_names)))
    for j, name in enumerate(eqs.input_names):
        if name in inputs:
            U[:, j] = inputs[name]
            continue
        spec = eqs.input_functions.get(name, eqs.input_defaults.get(name, 0.0))
        if isinstance(spec, numbers.Real):
            U[:, j] = float(spec)
        elif callable(spec) and not isinstance(spec, sp.Basic):
            U[:, j] = [float(spec(tk)) for tk in t]
        else:
            fn = sp.lambdify(eqs.t, sp.sympify(spec), modules="numpy")
            U[:, j] = np.broadcast_to(np.asarray(fn(t), dtype=float), t.shape)
    return np.ascontiguousarray(U)


class OutputSimulator:
    """Simulate a model's outputs on an experiment's recorded inputs; compiled once.

    Parameters
    ----------
    model : BondGraph or StateEquations
    experiment : Experiment
        Its ``t`` is the output grid and its ``inputs`` the zero-order-hold
        tables; model inputs it does not bind keep their default
        (``input_functions`` / ``input_defaults``).
    outputs : iterable of str, optional
        Outputs to return; default the experiment's outputs (all model outputs
        if it has none).
    backend : {"auto", "c", "numpy"}
        Evaluator backend (:func:`bondgraph.numerics.compile_model`).

    Examples
    --------
    >>> import numpy as np
    >>> from plants import library
    >>> from diagnosis.recording import Experiment
    >>> t = np.linspace(0.0, 2.0, 201)
    >>> exp = Experiment(t, {"F": np.ones_like(t)}, {"x": t}, {"F": "N", "x": "m"})
    >>> sim = OutputSimulator(library.build("mass-spring-damper"), exp)
    >>> round(float(sim()["x"][-1]), 4)   # analytic step response (m=1, b=0.4, k=4) at 2 s: 0.37458
    0.3746
    """

    def __init__(self, model, experiment, *, outputs=None, backend: str = "auto"):
        from diagnosis.errors import UnknownNameError
        from bondgraph.numerics.evaluate import compile_model
        from bondgraph.system import StateEquations

        self.equations = model if isinstance(model, StateEquations) else model.equations()
        self.model = compile_model(self.equations, backend=backend)
        self.experiment = experiment
        names = self.model.output_names
        wanted = list(outputs) if outputs is not None else (list(experiment.outputs) or list(names))
        for name in wanted:
            if name not in names:
                raise UnknownNameError("output", name, names, self.equations.name)
        self.output_names = tuple(wanted)
        self._out_idx = [self.model.output_index[n] for n in wanted]
        self.t = np.ascontiguousarray(experiment.t, dtype=float)
        self._past = _past_inputs(self.equations, experiment)
        self.U = input_matrix(self.equations, self.t, experiment.inputs, past=self._past)
        self._dt = np.diff(self.t)
        self._stiff_limit = None       # counted when first needed (_stiff_from)

    def on(self, experiment) -> "OutputSimulator":
        """The same compiled model and outputs on another experiment's grid and inputs.

        Compiling a model (:func:`bondgraph.numerics.compile_model`) takes about 0.2 s on pam; a fit
        that simulates the training and the held-out part reuses it.

        Parameters
        ----------
        experiment : Experiment

        Returns
        -------
        OutputSimulator
        """
        other = object.__new__(OutputSimulator)
        other.equations, other.model, other.experiment = self.equations, self.model, experiment
        other.output_names, other._out_idx = self.output_names, self._out_idx
        other.t = np.ascontiguousarray(experiment.t, dtype=float)
        other._past = _past_inputs(self.equations, experiment)
        other.U = input_matrix(self.equations, other.t, experiment.inputs, past=other._past)
        other._dt = np.diff(other.t)
        other._stiff_limit = self._stiff_limit
        return other

    def with_input(self, column: str, values) -> "OutputSimulator":
        """The same compiled model and experiment with input `column` replaced by `values` (one
        per sample, model units); this simulator is unchanged, so several can run at once.

        Raises
        ------
        UnknownNameError
            `column` is not an input of the model.
        """
        from diagnosis.errors import UnknownNameError

        if column not in self.model.input_index:
            raise UnknownNameError("input", column, self.model.input_names, self.equations.name)
        other = copy.copy(self)
        other.U = self.U.copy()
        other.U[:, self.model.input_index[column]] = values
        return other

    def initial_state(self, x0=None) -> np.ndarray:
        """The initial state vector from None (model default), a dict by name, or an array."""
        from diagnosis.errors import UnknownNameError

        x = self.model.default_state.copy()
        if isinstance(x0, dict):
            for name, value in x0.items():
                if name not in self.model.state_index:
                    raise UnknownNameError("state", name, self.model.state_names, self.equations.name)
                x[self.model.state_index[name]] = float(value)
        elif x0 is not None:
            x = np.asarray(x0, dtype=float).reshape(-1)
            if x.shape != self.model.default_state.shape:
                raise DiagnosisError(f"x0: expected {len(self.model.state_names)} states "
                                 f"({', '.join(self.model.state_names)}); found shape {x.shape}")
        return x

    def _hold_step(self) -> float:
        """The interval of a held (discrete) law: the sample interval, at most ``fixed_step``."""
        h = float(np.max(self._dt))
        return min(h, float(self.equations.fixed_step)) if self.equations.fixed_step else h

    def _sub_step(self, x, p) -> float:
        """The RK4 sub-step: the held law's interval, shorter where the start state's fastest mode
        needs it (:data:`_RK4_ACCURACY`; with held variables, at their initial values,
        :data:`_HELD_RK4_REACH`)."""
        h = self._hold_step()
        if x.size:
            try:
                J = self.model.jac_x(x, self.U[0], t=self.t[0], p=p)
            except (FloatingPointError, ValueError, ArithmeticError):
                J = np.full((1, 1), np.nan)
            if np.isfinite(J).all():
                h = min(h, self._rk4_step(float(np.max(np.abs(np.linalg.eigvals(J))))))
        return h

    def _rk4_step(self, lam: float) -> float:
        """The RK4 sub-step for a fastest mode of `lam` 1/s: :data:`_RK4_ACCURACY` over it (with
        held variables :data:`_HELD_RK4_REACH`); inf where `lam` is 0."""
        reach = _RK4_ACCURACY if self.equations.is_smooth else _HELD_RK4_REACH
        return reach / lam if lam > 0 else np.inf

    def _nesting(self, subs):
        """``(subs, every)``: sub-steps per sample interval and how many of them one held-law
        interval spans.  A model with held variables keeps its law's interval (Kikuuwe's friction
        on the pam: Z = h / J over 0.25 ms) and nests finer RK4 steps in it where a stiff law needs
        them (a sharp friction added at the seesaw: |lambda| h near 6 at 0.25 ms, past RK4's
        stability, seed 3535, case 019); before, a finer sub-step also shortened the law's interval."""
        if self.equations.is_smooth or not self.model.held_names:
            return subs, 1
        holds = np.maximum(1, np.ceil(self._dt / self._hold_step() - 1e-9)).astype(int)
        every = int(max(1, np.max(np.ceil(subs / holds - 1e-9))))
        return holds * every, every

    def run(self, params=None, x0=None) -> SimRun:
        """Simulate; states, inputs and the selected outputs at the experiment's times.

        Parameters
        ----------
        params : dict str -> float, optional
            Parameter overrides, SI units.
        x0 : dict str -> float or array_like, optional
            Initial state at ``experiment.t[0]``.

        Returns
        -------
        SimRun

        Raises
        ------
        ParameterError
            Unknown parameter name (known ones listed) or non-finite value.
        SimulationError
            Non-finite state (named, with the time) or a failed algebraic loop.
        """
        return self.run_batch([params], x0)[0]

    def run_batch(self, params_list, x0=None) -> list:
        """Simulate several parameter sets in the same compiled calls.

        A finite-difference Jacobian of a fit needs one run per parameter
        plus one; as a batch they cost about a third of separate runs.  Each run takes the
        integrator it would take alone: the runs that take the Rosenbrock method (:meth:`_stiff`)
        are batched apart from the others.

        Parameters
        ----------
        params_list : sequence of (dict str -> float or None)
            Parameter overrides of each run, SI units.
        x0 : optional
            Initial state shared by all runs (see :meth:`run`).

        Returns
        -------
        list of SimRun
            One per entry of `params_list`, in order.
        """
        m = self.model
        P = np.ascontiguousarray(np.vstack([m.param_vector(q) for q in params_list]))
        x_init = self.initial_state(x0)
        h = np.array([self._sub_step(x_init, P[i:i + 1]) for i in range(P.shape[0])])
        runs = [None] * P.shape[0]
        # a run takes the integrator it takes alone (RK4, or Rosenbrock where _stiff): a stiff
        # run batched with others must not put them on the stiff path (seed 4141, case 034: a Stribeck fit's
        # starts, batched with its guess 1000 times the fitted level, cost 2-9 times what they cost alone)
        self._run_rows(np.arange(P.shape[0]), P, h, x_init, runs)
        return runs

    def _run_rows(self, rows, P, h, x_init, runs, depth: int = 0) -> None:
        """Simulate the rows `rows` of `P` (sub-step `h` per row) into `runs`, each on the path it
        takes alone (:meth:`run_batch`), the RK4 runs in groups of alike sub-steps
        (:func:`_alike_steps`)."""
        stiff = np.array([self._stiff(self._substeps(h[i])[0]) for i in rows], dtype=bool)
        for group in _alike_steps(rows[~stiff], h) + [rows[stiff]]:
            if group.size:
                self._run_group(group, P, h, x_init, runs, depth)

    def _substeps(self, h_max: float):
        """``(subs, every)`` of :meth:`_nesting` for RK4 sub-steps of at most `h_max` s (and at
        least the experiment's ``substeps``) per sample interval; :meth:`_integrate` runs Rosenbrock
        where they are :meth:`_stiff`."""
        subs = np.maximum(getattr(self.experiment, "substeps", 1), np.ceil(self._dt / h_max - 1e-9)).astype(int)
        return self._nesting(subs)

    def _stiff(self, subs) -> bool:
        """Whether a run needing `subs` RK4 sub-steps per sample interval takes the Rosenbrock
        path: a smooth model past :meth:`_stiff_from`."""
        return bool(self.equations.is_smooth and subs.max() > self._stiff_from())

    def _stiff_from(self) -> int:
        """RK4 sub-steps per sample interval beyond which this model's runs cost less on the
        Rosenbrock path (``_STIFF_INTERVAL_COST`` over an RK4 sub-step's ``_RK4_STEP_COST``), at
        most ``_STIFF_SUBSTEPS``; counted once per model."""
        if self._stiff_limit is None:
            try:
                ops = sum(int(sp.count_ops(e)) for e in self.equations.f)
            except (TypeError, ValueError, AttributeError):    # an expression sympy cannot count
                ops = 0
            step = _RK4_STEP_COST[0] + _RK4_STEP_COST[1] * ops
            self._stiff_limit = int(min(_STIFF_SUBSTEPS, np.ceil(_STIFF_INTERVAL_COST / step)))
        return self._stiff_limit

    def _run_group(self, group, P, h, x_init, runs, depth: int = 0) -> None:
        """Simulate the rows `group` of `P` together (sub-step `h` per row), into `runs`.  A run on
        RK4 that left the finite numbers where its own states needed a sub-step below
        :data:`_RESTEP` of its own (:meth:`_step_along`) is simulated again with that one (at most
        :data:`_RESTEPS` times); the runs that stay finite are kept as they are."""
        h_max = float(np.min(h[group]))
        subs, every = self._substeps(h_max)
        # runs whose delayed inputs are late by the same times share their grid and inputs
        for delays, members in self._inputs_by_delay(P[group]).items():
            rows = group[np.asarray(members)]
            grid, U, at = self._delayed_inputs(delays)
            X, D, most = self._integrate(grid, U, self._grid_substeps(grid, subs), h_max, x_init, P[rows], every)
            if depth < _RESTEPS and not self._stiff(subs):
                need = np.array([self._step_along(X[at, k], U[at], P[i:i + 1], h_max)
                                 if not np.isfinite(X[at, k]).all() else np.inf for k, i in enumerate(rows)])
                finer = need < _RESTEP * h_max
                if finer.any():
                    h = h.copy()
                    h[rows[finer]] = need[finer]
                    self._run_rows(rows[finer], P, h, x_init, runs, depth + 1)
            else:
                finer = np.zeros(rows.size, dtype=bool)
            for k, i in enumerate(rows):
                if not finer[k]:
                    runs[i] = self._run(X[at, k], D[at, k], U[at], P[i:i + 1], most)

    def _step_along(self, X, U, p, h) -> float:
        """The RK4 sub-step (:meth:`_sub_step`'s rule) that a run gone to infinity with sub-step
        `h` needed: at :data:`_ALONG` of its states (`X`, at the samples, with their inputs `U`)
        up to the first where `h` was past RK4's stability (:data:`_RK4_STABLE`; the states after
        it are the instability's, not the model's), at least the sample interval over twice
        :data:`_STIFF_SUBSTEPS` (a smooth model then takes the Rosenbrock path, one with held
        variables fails as before).  :meth:`_sub_step` looks at the start state alone: a law stiff
        only in motion (a Dahl element: its relaxation rate is sigma |v| / F, 0 at rest) got the
        step of a model at rest and went to infinity when it moved (a carriage with Dahl
        friction, |lambda| h about 5 on 5 ms samples)."""
        finite = np.isfinite(X).all(axis=1)
        stop = X.shape[0] if finite.all() else int(np.argmin(finite))
        if stop < 2 or not X.shape[1]:
            return np.inf
        idx = np.unique(np.linspace(0, stop - 1, _ALONG).astype(int))
        try:
            J = self.model.jac_x(X[idx], U[idx], t=self.t[idx], p=np.repeat(p, idx.size, axis=0))
        except (FloatingPointError, ValueError, ArithmeticError, BondcosimError):
            return np.inf
        ok = np.isfinite(J).all(axis=(1, 2))
        lam = np.zeros(idx.size)
        lam[ok] = np.max(np.abs(np.linalg.eigvals(J[ok])), axis=1) if ok.any() else 0.0
        past = np.flatnonzero(lam * h > _RK4_STABLE)
        step = self._rk4_step(float(np.max(lam[:past[0] + 1] if past.size else lam)))
        return max(step, float(np.min(self._dt)) / (2 * _STIFF_SUBSTEPS))

    def _inputs_by_delay(self, P) -> dict:
        """Delays and values before the record (one tuple of ``(T, before)`` per distinct set) ->
        the rows of `P` simulated with them."""
        delays = self.equations.input_delays
        index = self.model.param_index

        def before(i, d):
            return float(P[i, index[d.before]]) if isinstance(d.before, str) else d.before

        groups = {}
        for i in range(P.shape[0]):
            key = tuple((float(P[i, index[d.time]]), before(i, d)) for d in delays.values())
            groups.setdefault(key, []).append(i)
        return groups

    def _delayed_inputs(self, delays: tuple):
        """``(grid, U, at)`` of :func:`bondgraph.numerics.input_delays.inputs_on_grid` for the
        delayed inputs late by `delays` (``(T, before)`` pairs, s and the input's unit, in
        ``input_delays`` order): the samples and the steps of a delayed command between them, the
        inputs held over each interval, and where the samples are."""
        from bondgraph.numerics.input_delays import inputs_on_grid
        if not delays:
            return self.t, self.U, np.arange(self.t.size)
        names = self.equations.input_delays
        return inputs_on_grid(self.equations, self.t, self.U, {n: T for n, (T, _) in zip(names, delays)},
                              {n: before for n, (_, before) in zip(names, delays)}, past=self._past)

    def _grid_substeps(self, grid, subs):
        """Sub-steps of each interval of `grid`: those of the sample interval it lies in, shared
        in proportion to its length (`subs` per sample interval)."""
        if grid is self.t:
            return subs
        parent = np.clip(np.searchsorted(self.t, grid[:-1], side="right") - 1, 0, self._dt.size - 1)
        h = self._dt[parent] / subs[parent]
        return np.maximum(1, np.ceil(np.diff(grid) / h - 1e-9)).astype(int)

    def _integrate(self, grid, U, subs, h_max, x_init, P, every=1):
        from diagnosis.errors import SimulationError

        m, n = self.model, P.shape[0]
        x = np.ascontiguousarray(np.tile(x_init, (n, 1)))
        d = np.ascontiguousarray(np.tile(m.default_held, (n, 1)))
        P = np.ascontiguousarray(P)
        if self._stiff(subs):
            # a fast mode RK4 would have to resolve (a smoothed Coulomb friction at rest, a
            # damper across a stiff gear): the L-stable linearly implicit Rosenbrock method steps over it
            from bondgraph.numerics.evaluate_stiff import rosenbrock_samples
            return rosenbrock_samples(m, grid, U, x, d, P)
        if subs.max() <= _STIFF_SUBSTEPS:
            X, D = m.rk4_samples(grid, U, subs, x, d, P, every=every)
            return X, D, int(subs.max())
        raise SimulationError(f"model {self.equations.name!r}: {subs.max()} RK4 sub-steps of "
                              f"{h_max:.3g} s per sample interval needed (stiff model with held "
                              "variables, or sparse samples); resample the recording",
                              time=float(self.t[0]))

    def _run(self, X, D, U, p, most) -> SimRun:
        """One run's outputs (and a named error where its states left the finite numbers)."""
        from diagnosis.errors import SimulationError

        m = self.model
        Xi, Di = np.ascontiguousarray(X), np.ascontiguousarray(D)
        bad = ~np.isfinite(Xi).all(axis=1)
        if bad.any():
            k = int(np.argmax(bad))
            names = [nm for nm, v in zip(m.state_names, Xi[k]) if not np.isfinite(v)]
            raise SimulationError(f"model {self.equations.name!r}: non-finite state(s) "
                                  f"{', '.join(names)} at t = {self.t[k]:.6g} s",
                                  time=float(self.t[k]))
        Y = (m.h(Xi, U, t=self.t, p=p, d=Di) if m.output_names
             else np.empty((self.t.size, 0)))
        outputs = {nm: Y[:, j].copy() for nm, j in zip(self.output_names, self._out_idx)}
        return SimRun(self.t, Xi, U, outputs, m.state_names, m.input_names, most)

    def __call__(self, params=None, x0=None) -> dict:
        """The selected outputs, dict name -> ndarray shape (n,), model units (see :meth:`run`)."""
        return self.run(params, x0).outputs


#: share of the noise by which halving the integration step may move the nominal's outputs
SUBSTEP_TOLERANCE = 0.1
#: most RK4 sub-steps per sample interval :func:`settle_substeps` tries
MOST_SUBSTEPS = 64


def settle_substeps(simulator, x0, noise: dict, *, run=None):
    """The experiment of `simulator` with as many RK4 sub-steps per sample as its outputs need.

    The simulator's step rule (:math:`h |\\lambda_{max}| \\le` 0.5 at the start) can leave an
    integration error above the noise where the dynamics are fast elsewhere than at the start (a
    valve's flow near its balance pressure).  Then the diagnosis would read the integration error as
    missing physics: on a PAM joint at 1 kHz, one sub-step per millisecond drifted the joint torque
    by 1.4 times its noise over 15 s, and a "constant mass flow" of 2e-9 kg/s was found in a
    recording of the nominal itself.  So the step is halved until halving it again moves no output
    by more than :data:`SUBSTEP_TOLERANCE` of its noise (RMS over the recording; an output with
    no noise estimate, 1e-4 of its spread), at most :data:`MOST_SUBSTEPS` sub-steps.

    Parameters
    ----------
    simulator : OutputSimulator
        The nominal model on the recording.
    x0 : dict or None
        The state the recording starts from.
    noise : dict str -> float
        Noise standard deviation per output, model units.
    run : SimRun, optional
        The simulator's run from `x0` when one was made already (the nominal residuals' run):
        not simulated again.

    Returns
    -------
    (Experiment, int)
        The experiment with ``substeps`` set (unchanged when the step rule sufficed or a run
        fails), and the sub-steps the step rule alone took.
    """
    from dataclasses import replace

    from diagnosis.errors import SimulationError

    exp = simulator.experiment
    try:
        run = run if run is not None else simulator.run(None, x0)
    except SimulationError:
        return exp, 1
    first = n = max(int(run.substeps), 1)
    y = run.outputs
    while 2 * n <= MOST_SUBSTEPS:
        finer = replace(exp, substeps=2 * n)
        try:
            y2 = simulator.on(finer)(None, x0)
        except SimulationError:
            break
        if _largest_change(y, y2, noise) <= SUBSTEP_TOLERANCE:
            break
        y, n = y2, 2 * n
    return (exp if n == first else replace(exp, substeps=n)), first


def _largest_change(y, y2, noise) -> float:
    """Largest RMS difference of two runs' outputs, each over its noise (1e-4 of its spread without)."""
    worst = 0.0
    for o, v in y.items():
        scale = noise.get(o) or 1e-4 * (float(np.std(v)) or 1.0)
        worst = max(worst, float(np.sqrt(np.mean((np.asarray(y2[o]) - v) ** 2))) / scale)
    return worst


def simulate_outputs(model, experiment, *, params=None, x0=None, outputs=None) -> dict:
    """Model outputs at ``experiment.t`` on the recorded inputs (see :class:`OutputSimulator`).

    Returns
    -------
    dict str -> ndarray, shape (n,)
        Outputs in the model's units.
    """
    return OutputSimulator(model, experiment, outputs=outputs)(params, x0)


def nrmse(measured, simulated) -> float:
    """Normalised root-mean-square error.

    .. math:: \\mathrm{NRMSE} = \\frac{\\sqrt{\\overline{(y - \\hat y)^2}}}{\\mathrm{std}(y)}

    Parameters
    ----------
    measured, simulated : array_like, shape (n,)

    Returns
    -------
    float
        0 for a perfect fit, 1 for a fit no better than the mean of `measured`.

    Raises
    ------
    DiagnosisError
        Shapes differ, non-finite values, or `measured` is constant.
    """
    y, s = np.asarray(measured, dtype=float), np.asarray(simulated, dtype=float)
    if y.shape != s.shape:
        raise DiagnosisError(f"nrmse: measured shape {y.shape} != simulated shape {s.shape}")
    if not (np.isfinite(y).all() and np.isfinite(s).all()):
        raise DiagnosisError("nrmse: non-finite values in measured or simulated signal")
    spread = float(np.std(y))
    if spread == 0.0:
        raise DiagnosisError("nrmse: the measured signal is constant (std 0); NRMSE is undefined")
    return float(np.sqrt(np.mean((y - s) ** 2)) / spread)


def noise_sigma(y, residual=None) -> float:
    """Measurement-noise standard deviation estimated from a recorded signal itself.

    White noise :math:`e` of variance :math:`\\sigma^2` gives second differences
    :math:`e_{k+1} - 2 e_k + e_{k-1}` of variance :math:`6\\sigma^2`, while a
    smooth signal sampled fast contributes little to them.  The few large ones at
    steps or kinks are set aside: those beyond :data:`TRIM` times the median
    absolute deviation's scale (x 1.4826, normal consistency); the root mean
    square of the rest, about their median, is the estimate:

    .. math:: \\hat\\sigma = \\mathrm{RMS}\\big(\\Delta^2 y \\;:\\; |\\Delta^2 y - m|
              \\le 4.5 \\cdot 1.4826\\,\\mathrm{MAD}(\\Delta^2 y)\\big) / \\sqrt 6

    The median absolute deviation alone is no estimate for a quantised signal:
    its second differences are whole multiples of the resolution :math:`q`, and
    so is their median, which missed the noise by -31 % to +37 % for
    :math:`q` between 0.25 and 3 noise standard deviations (at 1.2 a pure-noise
    output then seemed to hold a third of its variance in model error,
    ``tests/test_diagnosis_noise.py``); the trimmed RMS is within 2 %.

    A signal that is not smooth at the sampling rate (a resonance near a third
    of it) inflates this.  Given the `residual` of a model on the same samples
    (measured minus simulated), the same estimate on the residual is taken
    when smaller: the model removes what it explains of the signal's fast
    content and leaves the noise, which both share.

    When most second differences are exactly zero (a quantised signal that
    moves slowly) the quantisation noise :math:`q/\\sqrt{12}` of the
    resolution :math:`q` (the smallest step, when nearly every step is a whole
    multiple of it) is returned instead, if larger.

    Parameters
    ----------
    y : array_like, shape (n,), n >= 3
    residual : array_like, shape (n,), optional
        ``y`` minus a model's simulation of it (finite).

    Returns
    -------
    float
        Same unit as `y`.

    Examples
    --------
    A 70 Hz sine sampled at 200 Hz is not smooth at the sampling rate; a model
    that reproduces it leaves only the 0.01 noise:

    >>> import numpy as np
    >>> t = np.arange(4000) / 200.0
    >>> clean = np.sin(2 * np.pi * 70 * t)
    >>> y = clean + np.random.default_rng(0).normal(0.0, 0.01, t.size)
    >>> float(round(noise_sigma(y), 2)), float(round(noise_sigma(y, y - clean), 3))
    (0.92, 0.01)
    """
    y = np.asarray(y, dtype=float).reshape(-1)
    if y.size < 3:
        raise DiagnosisError(f"noise_sigma: need at least 3 samples; found {y.size}")
    sigma = _trimmed_sigma(y)
    if residual is not None:
        r = np.asarray(residual, dtype=float).reshape(-1)
        if r.shape == y.shape and np.isfinite(r).all():
            sigma = min(sigma, _trimmed_sigma(r))
    return max(sigma, _quantum(y) / np.sqrt(12.0))


def _quantum(y: np.ndarray) -> float:
    """The resolution of a quantised signal: its smallest step, when (nearly) every step is a
    whole multiple of it; 0 for a signal that is not quantised."""
    steps = np.abs(np.diff(y))
    steps = steps[steps > 0]
    if not steps.size:
        return 0.0
    q = float(steps.min())
    ratio = steps / q
    whole = np.abs(ratio - np.round(ratio)) < 0.01 + 1e-9 * ratio   # rounding of the written values
    return q if np.mean(whole) > 0.9 else 0.0


#: second differences farther from their median than this many robust scales are steps or kinks
TRIM = 4.5


def _trimmed_sigma(y: np.ndarray) -> float:
    """The noise of `y` from its second differences: their RMS about the median, without those
    beyond :data:`TRIM` robust scales (1.4826 MAD); 0 where most of them are exactly equal."""
    d2 = np.diff(y, 2)
    deviation = np.abs(d2 - np.median(d2))
    scale = 1.4826 * float(np.median(deviation))
    if scale == 0.0:
        return 0.0
    kept = deviation[deviation <= TRIM * scale]
    return float(np.sqrt(np.mean(kept ** 2) / 6.0))


@dataclass
class Residuals:
    """Measured against simulated outputs of one experiment (model units).

    Attributes
    ----------
    t : ndarray, shape (n,)
        Times, s.
    measured, simulated, residual : dict str -> ndarray, shape (n,)
        Per output; ``residual = measured - simulated``.
    noise : dict str -> float
        Measurement-noise std of each measured output (:func:`noise_sigma` of the
        measurement and of the residual).
    nrmse : dict str -> float
        Per output (:func:`nrmse`).
    run : SimRun
        The simulation (states for regime location).
    """

    t: np.ndarray
    measured: dict
    simulated: dict
    residual: dict
    noise: dict
    nrmse: dict
    run: SimRun


def residuals(model, experiment, *, params=None, x0=None, outputs=None,
              simulator: OutputSimulator | None = None, run: SimRun | None = None) -> Residuals:
    """Simulate the model on the experiment and compare with its measured outputs.

    Parameters
    ----------
    model : BondGraph or StateEquations
    experiment : Experiment
    params, x0 : optional
        As :meth:`OutputSimulator.run`.
    outputs : iterable of str, optional
        Default: every measured output.
    simulator : OutputSimulator, optional
        A compiled simulator of this model and experiment to reuse.
    run : SimRun, optional
        The model's run on these inputs, already simulated (`params` and `x0` are then not used).

    Returns
    -------
    Residuals
    """
    names = list(outputs) if outputs is not None else list(experiment.outputs)
    sim = simulator or OutputSimulator(model, experiment, outputs=names)
    run = run if run is not None else sim.run(params, x0)
    measured = {n: np.asarray(experiment.outputs[n], dtype=float) for n in names}
    simulated = {n: run.outputs[n] for n in names}
    residual = {n: measured[n] - simulated[n] for n in names}
    return Residuals(experiment.t, measured, simulated, residual,
                     {n: noise_sigma(measured[n], residual[n]) for n in names},
                     {n: nrmse(measured[n], simulated[n]) for n in names}, run)
