"""Simulation of state equations over a time span.

:func:`simulate` integrates :math:`\\dot x = f(t, x, u, z, d, p)` from a
:class:`~bondgraph.system.StateEquations` (compiled by
:func:`bondgraph.numerics.evaluate.compile_model`) and returns a
:class:`~bondgraph.numerics.results.SimulationResult` with every state, algebraic
unknown, held variable, input and output by name.

Two integration regimes
-----------------------
Smooth models (``eqs.is_smooth``: no held variables, no ``fixed_step``)
    :func:`scipy.integrate.solve_ivp`.  ``method="auto"`` evaluates the
    compiled Jacobian at the initial point and takes the fastest decay rate
    :math:`\\lambda_f = \\max_i(-\\mathrm{Re}\\,\\lambda_i)`; if
    :math:`\\lambda_f (t_1 - t_0) > 10^3` the model is stiff and ``"Radau"``
    (up to 200 states; ``"BDF"`` above, cheaper per step) is used with the
    compiled Jacobian, otherwise ``"LSODA"`` (which still switches to BDF by
    itself should stiffness appear later; it is given the Jacobian too).
    Above 400 states the eigenvalue test is skipped and ``"LSODA"`` is used.
    Any ``solve_ivp`` method may be passed instead; ``"RK4"`` integrates a
    smooth model with the fixed-step scheme below.  Zero-order-hold table
    inputs are piecewise constant, so the solver is restarted at each table
    breakpoint instead of stepping over the jump.
Non-smooth models (held variables or ``fixed_step``)
    Classic fixed-step RK4.  Each output interval is divided into equal
    sub-steps no longer than ``min(dt, fixed_step)`` (whichever are given).
    At the start of every sub-step the held variables are replaced by
    ``held_update`` (with ``step`` = the sub-step) and held over it.  Inputs
    are zero-order held over each output interval (as a co-simulation master
    holds them over a communication step).

Inputs
------
``inputs`` maps input names to a float, a callable ``t -> float``, a string
expression in ``t`` (e.g. ``"0.5*sin(2*pi*t)"``), a sympy expression in ``t``,
or a table ``(times, values)``.  Tables are **zero-order hold**: the value
at ``t`` is ``values[k]`` for ``times[k] <= t < times[k+1]``, ``values[0]``
before the first time and ``values[-1]`` after the last.  (For linear
interpolation pass ``lambda t: numpy.interp(t, times, values)``.)  An input
not given takes its ``input_functions`` entry, else its ``input_defaults``.

Recorded values
---------------
At each output time: the states, the algebraic unknowns (solved there), the
held values in effect over the last sub-step (``held_initial`` at the start),
the inputs (tables right-continuous) and the outputs ``h`` of those.  An
output whose name is also a state (or another signal) gets the suffix
``_output``.
"""
from __future__ import annotations

import math
import numbers

import numpy as np
import sympy as sp

from ..errors import ArgumentError, DomainError, ExpressionError, SimulationError, UnknownNameError
from .memory import check_result_size
from .progress import Progress
from .evaluate import compile_model
from .input_delays import before_values, delay_values
from ..guards import check_param_bounds, guard_function, guard_values, raise_violation
from .results import SimulationResult
from ..symbols import as_expression
from ..system import StateEquations

__all__ = ["simulate", "IVP_METHODS"]

#: Methods of :func:`scipy.integrate.solve_ivp` accepted by name.
IVP_METHODS = ("RK45", "RK23", "DOP853", "Radau", "BDF", "LSODA")
_IMPLICIT = ("Radau", "BDF", "LSODA")
_STIFF_RATIO = 1e3          # lambda_f * span above which "auto" picks an implicit method
_EIG_MAX_STATES = 400        # above: no eigenvalue test, LSODA detects stiffness itself
_RADAU_MAX_STATES = 200
_DEFAULT_POINTS = 1000       # output intervals when output_interval is not given (smooth)
_MAX_DEFAULT_POINTS = 10000  # cap for non-smooth models


def simulate(system, t_span, *, inputs=None, x0=None, params=None, method="auto", dt=None,
             output_interval=None, backend="auto", rtol=1e-8, atol=1e-10,
             progress=False, max_nfev: int = 500_000, held0=None) -> SimulationResult:
    """Simulate a model over a time span.

    Parameters
    ----------
    system : StateEquations or object with ``equations()``
        The model.
    t_span : (float, float)
        Start and end time ``(t0, t1)``, s, with ``t1 > t0``.
    inputs : dict str -> float | callable | str | sympy.Expr | (times, values), optional
        Input signals (see the module docstring; tables are zero-order hold).
    x0 : array_like, shape (n_states,), or dict str -> float, optional
        Initial state; a dict overrides ``initial_state`` by name.  Default
        ``initial_state`` (0 for states without an entry).
    params : dict str -> float or array_like, shape (n_params,), optional
        Parameters; a dict overrides ``param_values`` by name.
    method : str or scipy OdeSolver class
        ``"auto"`` (see the module docstring), ``"RK4"`` (fixed step), or a
        :func:`~scipy.integrate.solve_ivp` method (smooth models only).
    dt : float, s, optional
        Largest fixed step (non-smooth models and ``"RK4"``); for the
        ``solve_ivp`` methods, their ``max_step``.
    output_interval : float, s, optional
        Spacing of the recorded time points (the last one is ``t1``).
        Default: span/1000 for smooth models; for fixed-step integration the
        smallest multiple of the sub-step giving at most 10000 points.
    backend : {"auto", "c", "numpy"}
        Evaluator backend (:func:`bondgraph.numerics.evaluate.compile_model`).
    rtol, atol : float
        Tolerances of the ``solve_ivp`` methods (states in SI units).
    progress : bool
        Print a progress line to stderr.
    held0 : array_like, shape (n_held,), or dict str -> float, optional
        Initial held (discrete) values, e.g. to continue a run where an
        earlier one stopped; default ``held_initial``.
    max_nfev : int
        Budget of right-hand-side evaluations of the ``solve_ivp`` methods
        (about 10 s of work): a solver grinding towards a singularity (a
        volume going to zero, a stiff transient it cannot step over) stops
        with a :class:`SimulationError` naming the time and the fastest-changing
        states instead of running for ever.

    Returns
    -------
    SimulationResult
        ``info`` holds ``method``, ``backend``, ``nfev`` and ``sub_step`` (s,
        fixed-step) or ``stiffness`` (:math:`\\lambda_f (t_1 - t_0)`, auto).

    Raises
    ------
    UnknownNameError
        An input (or ``x0`` state) name the model does not have; lists the known ones.
    ExpressionError
        An input string that does not parse or uses names other than ``t``,
        or an input callable that fails at ``t0``.
    ParameterError
        An unknown parameter name, a non-finite parameter value, or one
        outside its declared range (a negative mass).
    ArgumentError
        A wrong shape, span, step or method (a ``ValueError``).
    OutputTooLargeError
        The samples asked for would not fit in memory (a ``MemoryError``),
        raised before any work.
    SimulationError
        Solver failure, non-finite state (named), or an unsolvable algebraic loop.
    DomainError
        (a SimulationError) a guard of the model (:mod:`bondgraph.guards`,
        e.g. a chamber volume >= 0) is left at a recorded time point: names
        the guard, its value and the time.
    """
    eqs = system if isinstance(system, StateEquations) else system.equations()
    t0, t1 = _span(t_span)
    for label, value in (("dt", dt), ("output_interval", output_interval)):
        if value is not None and not (isinstance(value, numbers.Real) and math.isfinite(value) and value > 0):
            raise ArgumentError(f"{label}: expected a positive number of seconds; found {value!r}", name=label)
    if output_interval is not None:   # refuse a result that cannot fit before compiling anything
        n_signals = 1 + len(eqs.states) + len(eqs.inputs) + len(eqs.outputs) + len(eqs.held)
        check_result_size(t1 - t0, output_interval, n_signals, what=f"simulation of {eqs.name!r}")
    model = compile_model(eqs, backend=backend)
    x_init = _initial_state(model, x0)
    p = model.param_vector(params)
    check_param_bounds(eqs, p)
    values = dict(zip(model.param_names, p[0]))
    plan = _InputPlan(eqs, inputs, t0, delays=delay_values(eqs, values), befores=before_values(eqs, values))
    d0 = _initial_held(model, held0).reshape(1, -1)
    fixed = (not eqs.is_smooth) or method == "RK4"
    if not eqs.is_smooth and method not in ("auto", "RK4"):
        raise ArgumentError(f"model {eqs.name!r} is not smooth (held variables or fixed_step="
                         f"{eqs.fixed_step}); it is integrated with fixed-step 'RK4', so method "
                         f"must be 'auto' or 'RK4'; found {method!r}")
    bar = Progress(t1 - t0, fmt=f"simulate {eqs.name}: {{percentage:5.1f}} %  {{desc}}", enabled=progress,
                   start=t0, value_fmt="t = {:.6g} s")
    try:
        if fixed:
            h_max = min([v for v in (dt, eqs.fixed_step) if v] or [output_interval or (t1 - t0) / _DEFAULT_POINTS])
            if output_interval is None:
                output_interval = h_max * max(1, math.ceil((t1 - t0) / _MAX_DEFAULT_POINTS / h_max - 1e-9))
            times = _grid(t0, t1, output_interval)
            X, D, info = _integrate_fixed(model, plan, x_init, d0, p, times, h_max, bar)
        else:
            times = _grid(t0, t1, output_interval or (t1 - t0) / _DEFAULT_POINTS)
            X, info = _integrate_smooth(model, plan, x_init, p, d0, times, method, dt, rtol, atol,
                                        bar, max_nfev)
            D = np.repeat(d0, times.size, axis=0)
    finally:
        bar.close()
    info = {"backend": model.backend, **info}
    return _assemble(model, plan, times, X, D, p, info)


# -- arguments ------------------------------------------------------------------------

def _span(t_span):
    try:
        t0, t1 = (float(v) for v in t_span)
    except (TypeError, ValueError):
        raise ArgumentError(f"t_span: expected (t0, t1) in seconds; found {t_span!r}") from None
    if not (math.isfinite(t0) and math.isfinite(t1) and t1 > t0):
        raise ArgumentError(f"t_span: expected finite t0 < t1; found ({t0}, {t1})")
    return t0, t1


def _grid(t0, t1, interval):
    n = int(math.floor((t1 - t0) / interval + 1e-9))
    times = t0 + interval * np.arange(n + 1)
    if t1 - times[-1] > 1e-9 * interval:
        times = np.append(times, t1)
    else:
        times[-1] = t1
    return times


def _initial_state(model, x0):
    names = model.state_names
    if x0 is None:
        x = model.default_state.copy()
    elif isinstance(x0, dict):
        x = model.default_state.copy()
        for name, value in x0.items():
            if name not in model.state_index:
                raise UnknownNameError("state", name, names, model.equations.name)
            x[model.state_index[name]] = float(value)
    else:
        x = np.array(x0, dtype=float)
        if x.shape != (len(names),):
            raise ArgumentError(f"x0: expected shape ({len(names)},) (states {', '.join(names)}); "
                             f"found {x.shape}")
    bad = [n for n, v in zip(names, x) if not math.isfinite(v)]
    if bad:
        raise ArgumentError(f"x0: non-finite initial value of state(s) {', '.join(bad)}")
    return x


def _initial_held(model, held0):
    names = model.held_names
    d = model.default_held.copy()
    if held0 is None:
        return d
    if isinstance(held0, dict):
        for name, value in held0.items():
            if name not in names:
                raise UnknownNameError("held variable", name, names, model.equations.name)
            d[names.index(name)] = float(value)
    else:
        d = np.array(held0, dtype=float)
        if d.shape != (len(names),):
            raise ArgumentError(f"held0: expected shape ({len(names)},) (held variables "
                                f"{', '.join(names) or '(none)'}); found {d.shape}", name="held0")
    if not np.all(np.isfinite(d)):
        raise ArgumentError("held0: non-finite initial held value(s)", name="held0")
    return d


class _InputPlan:
    """Input vector u(t) from constants, functions of t and zero-order-hold tables; a delayed
    input (``eqs.input_delays``, its delay in `delays`, s) is its source at ``t - T``, and its
    ``before`` value (in `befores`, or the model's) while ``t - T < t0``: exact on tables, whose
    steps it moves by ``T``."""

    def __init__(self, eqs, inputs, t0, delays=None, befores=None):
        names = eqs.input_names
        given = dict(inputs or {})
        for name in given:
            if name not in names:
                raise UnknownNameError("input", name, names, eqs.name)
            if name in eqs.input_delays:
                raise ArgumentError(f"input {name!r} of model {eqs.name!r} is input "
                                    f"{eqs.input_delays[name].source!r} delayed: give that one", name=name)
        self._t = eqs.t
        self.base = np.array([float(eqs.input_defaults.get(n, 0.0)) for n in names])
        self.funcs, self.tables = [], []
        for i, name in enumerate(names):
            if name in given:
                spec = given[name]
            else:
                spec = eqs.input_functions.get(name, eqs.input_defaults.get(name, 0.0))
            self._add(i, name, spec, t0)
        delays = delays or {}
        befores = before_values(eqs) if befores is None else befores
        self.t0 = t0
        self.late = []      # (column, source column, T, before, the source's table moved by T)
        for n, d in eqs.input_delays.items():
            j, T = names.index(d.source), float(delays[n])
            table = next(((tt + T, values) for i, tt, values in self.tables if i == j), None)
            before = float(self._undelayed(t0)[j]) if befores[n] is None else befores[n]
            self.late.append((names.index(n), j, T, before, table))
        # the integration restarts where a table steps, not at every sample of it: a recording
        # of held levels changes at few of its samples (a 1 kHz table held over 7 samples cut 3 s
        # of a DC motor into 3000 LSODA runs instead of 430)
        steps = {b for _, tt, values in self.tables for b in _steps(tt, values)}
        for _, _, T, _, table in self.late:    # a delayed table steps T after its source
            steps |= {t0 + T} | (set(_steps(*table)) if table else set())
        self.breakpoints = _merged(sorted(steps))

    def _add(self, i, name, spec, t0):
        owner = f"input {name!r}"
        if isinstance(spec, bool) or spec is None:
            raise ExpressionError(f"{owner}: expected a number, callable, expression or "
                                  f"(times, values) table; found {spec!r}", owner=name)
        if isinstance(spec, numbers.Real):
            self.base[i] = float(spec)
            return
        if isinstance(spec, (str, sp.Basic)):
            expr = as_expression(spec, {"t": self._t}, owner=owner)
            if not expr.free_symbols:
                self.base[i] = float(expr)
                return
            fn = sp.lambdify(self._t, expr, modules="numpy")
            self.funcs.append((i, lambda t, fn=fn: float(fn(t)), name, spec))
        elif callable(spec):
            self.funcs.append((i, lambda t, fn=spec: float(fn(t)), name, spec))
        elif isinstance(spec, (tuple, list)) and len(spec) == 2:
            self.tables.append((i, *_table(name, spec)))
            return
        else:
            raise ExpressionError(f"{owner}: expected a number, callable, string in t, sympy "
                                  f"expression or (times, values) table; found "
                                  f"{type(spec).__name__}", owner=name)
        i, fn, _, text = self.funcs[-1]
        try:
            value = fn(t0)
        except Exception as exc:   # a user callable may raise anything
            raise ExpressionError(f"{owner}: evaluating {text!r} at t = {t0} failed: "
                                  f"{exc.__class__.__name__}: {exc}", owner=name,
                                  expression=str(text)) from None
        if not math.isfinite(value):
            raise ExpressionError(f"{owner}: {text!r} is {value} at t = {t0}", owner=name,
                                  expression=str(text))

    def vector(self, t, hold_from=None):
        """u at time t, shape (1, n_inputs); tables evaluated at `hold_from` if given."""
        u = self._undelayed(t, hold_from)
        tt = t if hold_from is None else hold_from
        for i, j, T, before, table in self.late:
            if tt < self.t0 + T:
                u[i] = before
            elif table is not None:
                u[i] = table[1][max(0, np.searchsorted(table[0], tt, side="right") - 1)]
            else:
                u[i] = self._undelayed(t - T)[j]
        return u.reshape(1, -1)

    def _undelayed(self, t, hold_from=None):
        u = self.base.copy()
        for i, fn, _, _ in self.funcs:
            u[i] = fn(t)
        tt = t if hold_from is None else hold_from
        for i, times, values in self.tables:
            u[i] = values[max(0, np.searchsorted(times, tt, side="right") - 1)]
        return u

    def matrix(self, times):
        """u at each time, shape (n_times, n_inputs)."""
        if self.late:
            return np.vstack([self.vector(t) for t in times])
        U = np.repeat(self.base.reshape(1, -1), times.size, axis=0)
        for i, fn, _, _ in self.funcs:
            U[:, i] = [fn(t) for t in times]
        for i, tt, values in self.tables:
            U[:, i] = values[np.maximum(0, np.searchsorted(tt, times, side="right") - 1)]
        return U


def _steps(times, values) -> list:
    """The times at which a zero-order-hold table's value changes."""
    values = np.asarray(values, dtype=float)
    changed = values[1:] != values[:-1]
    return [float(b) for b in np.asarray(times, dtype=float)[1:][changed]]


def _merged(points: list) -> list:
    """Sorted `points` without those a rounding error away from the one before (a delayed table's
    step ``b + T`` that meets another step would otherwise leave an interval of 1e-16 s)."""
    merged = []
    for b in points:
        if merged and b - merged[-1] <= 1e-12 * max(1.0, abs(b)):
            merged[-1] = b      # the later one: a table held from there has stepped in both
        else:
            merged.append(b)
    return merged


def _table(name, spec):
    times, values = (np.asarray(v, dtype=float) for v in spec)
    if times.ndim != 1 or times.shape != values.shape or times.size == 0:
        raise ArgumentError(f"input {name!r}: a table must be (times, values), two 1-D arrays of "
                         f"equal length; found shapes {times.shape} and {values.shape}")
    if not (np.isfinite(times).all() and np.isfinite(values).all()):
        raise ArgumentError(f"input {name!r}: table contains non-finite numbers")
    if np.any(np.diff(times) <= 0):
        raise ArgumentError(f"input {name!r}: table times must be strictly increasing")
    return times, values


# -- integration ------------------------------------------------------------------------

def _check_finite(model, x, t, what="state"):
    if not np.isfinite(x).all():
        bad = [n for n, v in zip(model.state_names, np.ravel(x)) if not math.isfinite(v)]
        raise SimulationError(f"model {model.equations.name!r}: non-finite {what} of "
                              f"{', '.join(bad)} at t = {t:.9g} s", time=float(t))


def _choose_method(model, plan, x, p, d, t0, span):
    nx = x.size
    if nx > _EIG_MAX_STATES:
        return "LSODA", None
    J = model.jac_x(x, plan.vector(t0)[0], t=t0, p=p, d=d)
    if not np.isfinite(J).all():
        return "LSODA", None
    fast = max(0.0, float(np.max(-np.linalg.eigvals(J).real)))
    ratio = float(fast * span)
    if ratio > _STIFF_RATIO:
        return ("Radau" if nx <= _RADAU_MAX_STATES else "BDF"), ratio
    return "LSODA", ratio


def _give_up(model, method, max_nfev, t, x, dx, u, d, p):
    """Raise the SimulationError of an exhausted evaluation budget, naming the states
    that change fastest relative to their size."""
    rate = np.abs(dx) / np.maximum(np.abs(x), 1e-12)
    worst = [model.state_names[i] for i in np.argsort(-rate)[:3] if rate[i] > 0]
    eqs = model.equations
    guards = ""
    if eqs.guards:   # the values of the domain guards there often show the singularity
        values = guard_function(eqs)(np.array([t]), np.reshape(x, (1, -1)), u, d, p)[0]
        guards = "; domain guards there: " + ", ".join(
            f"{g.name} = {v:.4g}{' ' + g.guard.unit if g.guard.unit not in ('', '1') else ''}"
            for g, v in zip(eqs.guards, values))
    raise SimulationError(
        f"model {eqs.name!r}: {method} gave up after {max_nfev} right-hand-side "
        f"evaluations at t = {t:.9g} s; fastest-changing states (relative): {', '.join(worst)}"
        f"{guards}. The model may be near a singularity there; check the initial state, or raise "
        "max_nfev (or try method='Radau')", time=float(t))


def _integrate_smooth(model, plan, x0, p, d, times, method, dt, rtol, atol, bar, max_nfev):
    from scipy.integrate import solve_ivp

    t0, t1 = times[0], times[-1]
    X = np.empty((times.size, x0.size))
    X[0] = x0
    info = {"method": method}
    if x0.size == 0:
        return X, {"method": None, "nfev": 0}
    if method == "auto":
        method, info["stiffness"] = _choose_method(model, plan, x0, p, d, t0, t1 - t0)
    elif isinstance(method, str) and method not in IVP_METHODS:
        raise ArgumentError(f"method: expected 'auto', 'RK4' or one of {', '.join(IVP_METHODS)}; "
                         f"found {method!r}")
    info["method"] = method if isinstance(method, str) else getattr(method, "__name__", str(method))
    hold = [t0]
    counts = {"nfev": 0, "njev": 0}

    def rhs(t, x):
        bar.update_to(t)
        _check_finite(model, x, t)
        x2 = np.ascontiguousarray(x, dtype=float).reshape(1, -1)
        dx = model._call("f", np.array([t]), x2, plan.vector(t, hold[0]), p, d)[0]
        _check_finite(model, dx, t, "time derivative")
        counts["nfev"] += 1
        if counts["nfev"] > max_nfev:
            _give_up(model, info["method"], max_nfev, t, x, dx, plan.vector(t, hold[0]).reshape(1, -1),
                     np.asarray(d).reshape(1, -1), p)
        return dx

    def jac(t, x):
        counts["njev"] += 1
        J = model.jac_x(x, plan.vector(t, hold[0])[0], t=t, p=p, d=d)
        if not np.isfinite(J).all():   # an implicit method would fail in its LU with a bare ValueError
            rows = sorted({model.state_names[i] for i in np.argwhere(~np.isfinite(J))[:, 0]})
            raise SimulationError(f"model {model.equations.name!r}: non-finite Jacobian of the time derivative "
                                  f"of {', '.join(rows)} at t = {t:.9g} s, which {info['method']} needs: the "
                                  "model is at a singularity there or a law has an infinite slope (a square root "
                                  "at 0); method='LSODA' or 'DOP853' need no Jacobian", time=float(t))
        return J

    options = {"rtol": rtol, "atol": atol}
    events = _guard_events(model.equations, plan, p, d, hold)
    if events:
        options["events"] = events
    if dt is not None:
        options["max_step"] = dt
    if info["method"] in _IMPLICIT:
        options["jac"] = jac
    cuts = [t0, *[b for b in plan.breakpoints if t0 < b < t1], t1]
    x = x0
    for a, b in zip(cuts[:-1], cuts[1:]):
        hold[0] = a   # tables keep their value at a over [a, b]
        mask = (times > a) & (times <= b)
        t_eval = times[mask]
        if not t_eval.size or t_eval[-1] != b:
            t_eval = np.append(t_eval, b)
        sol = solve_ivp(rhs, (a, b), x, method=method, t_eval=t_eval, **options)
        if sol.status == 1:   # a guard's terminal event: the state left the physical domain
            te = float(sol.t_events[[len(e) > 0 for e in sol.t_events].index(True)][0])
            xe = np.concatenate([y for y in sol.y_events if len(y)])[:1]
            _check_guards(model.equations, plan, np.array([te]), xe,
                          np.asarray(d).reshape(1, -1), p, events=True)
        if sol.status < 0 or sol.y.shape[1] != t_eval.size:
            tf = float(sol.t[-1]) if np.size(sol.t) else a
            raise SimulationError(f"model {model.equations.name!r}: {info['method']} failed at "
                                  f"t = {tf:.9g} s: {sol.message}", time=tf)
        X[mask] = sol.y.T[:mask.sum()]
        x = sol.y[:, -1]
    info.update(counts)
    return X, info


def _integrate_fixed(model, plan, x0, d0, p, times, h_max, bar):
    """Classic RK4 with held variables updated at each sub-step start; one
    compiled call per output interval (``bc_rk4``)."""
    X = np.empty((times.size, x0.size))
    D = np.empty((times.size, d0.shape[1]))
    X[0], D[0] = x0, d0[0]
    x, d = x0.reshape(1, -1).copy(), d0.copy()
    nfev, h = 0, h_max
    for k in range(times.size - 1):
        ta, tb = times[k], times[k + 1]
        bar.update_to(ta)
        u = plan.vector(ta)   # zero-order hold over the output interval
        m = max(1, math.ceil((tb - ta) / h_max - 1e-9))
        h = (tb - ta) / m
        model._rk4(ta, h, m, x, u, p, d)
        nfev += 4 * m
        X[k + 1], D[k + 1] = x[0], d[0]
        if not np.isfinite(x).all():   # a guard left on the way names the cause better
            _check_guards(model.equations, plan, times[:k + 2], X[:k + 2], D[:k + 2], p)
            _check_finite(model, x, tb)
    return X, D, {"method": "RK4", "sub_step": float(h), "nfev": nfev}


# -- result ---------------------------------------------------------------------------

def _algebraic_along(model, times, X, U, D, p):
    if not model.algebraic_names:
        return np.empty((times.size, 0))
    try:
        return model.solve_algebraic(X, U, t=times, p=p, d=D)
    except SimulationError:
        pass
    # batch start from the initial guess failed somewhere: continue row by row
    Z = np.empty((times.size, len(model.algebraic_names)))
    z = None
    for k in range(times.size):
        z = model.solve_algebraic(X[k], U[k], t=times[k], p=p, d=D[k], z0=z)
        Z[k] = z
    return Z


def _check_guards(eqs, plan, times, X, D, p, *, events=False):
    """Raise DomainError at the first recorded point where a guard of `eqs` is left
    (`events`: the points are guard crossings found by the solver; the value may be the bound)."""
    if not eqs.guards:
        return
    values = guard_values(eqs, times, X, plan.matrix(times), D, p)
    if events:   # at a crossing the value is the bound to rounding: report the guard crossed
        lo = np.array([-np.inf if g.guard.min is None else g.guard.min for g in eqs.guards])
        hi = np.array([np.inf if g.guard.max is None else g.guard.max for g in eqs.guards])
        j = int(np.argmin(np.minimum(np.abs(values[0] - lo), np.abs(values[0] - hi))))
        g = eqs.guards[j]
        raise DomainError(g.message(float(values[0, j]), float(times[0]), eqs.name),
                          variable=g.name, value=float(values[0, j]), time=float(times[0]),
                          owner=g.owner)
    raise_violation(eqs.guards, values, times, eqs.name)


def _guard_events(eqs, plan, p, d, hold):
    """solve_ivp terminal events, one per guard bound (value - bound changes sign)."""
    if not eqs.guards:
        return []
    fn = guard_function(eqs)
    d2 = np.asarray(d, dtype=float).reshape(1, -1)

    def make(j, bound, sign):
        def event(t, x):
            u = plan.vector(t, hold[0]).reshape(1, -1)
            return sign * (fn(np.array([t]), x.reshape(1, -1), u, d2, p)[0, j] - bound)
        event.terminal = True
        event.direction = -1
        return event
    out = []
    for j, g in enumerate(eqs.guards):
        if g.guard.min is not None:
            out.append(make(j, g.guard.min, 1.0))
        if g.guard.max is not None:
            out.append(make(j, g.guard.max, -1.0))
    return out


def _assemble(model, plan, times, X, D, p, info):
    eqs = model.equations
    _check_guards(eqs, plan, times, X, D, p)
    U = plan.matrix(times)
    Z = _algebraic_along(model, times, X, U, D, p)
    Y = (model.h(X, U, t=times, p=p, d=D, z=Z) if model.output_names
         else np.empty((times.size, 0)))
    signals, units, kinds = {}, {}, {}
    for names, values, kind in ((model.state_names, X, "state"),
                                (model.algebraic_names, Z, "algebraic"),
                                (model.held_names, D, "held"),
                                (model.input_names, U, "input"),
                                (model.output_names, Y, "output")):
        for j, name in enumerate(names):
            key = name if name not in signals else f"{name}_{kind}"
            signals[key], units[key], kinds[key] = values[:, j], eqs.units.get(name, ""), kind
    info = {"model": eqs.name, **info}
    return SimulationResult(times, signals, units=units, kinds=kinds, info=info)
