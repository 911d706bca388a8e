"""Physical-domain guards: conditions a model's variables must keep.

A :class:`Guard` says that a quantity -- any expression of states, inputs,
parameters and held variables, e.g. a chamber volume
:math:`V = D_1 l^2 + D_2 l + D_3` or an absolute pressure -- stays inside
``[min, max]``.  Elements declare their own (:meth:`Element.guards
<bondgraph.elements.base.Element.guards>`, the ``guards=`` argument of
:class:`~bondgraph.elements.EquationElement`), a graph adds more with
:meth:`BondGraph.add_guard <bondgraph.graph.BondGraph.add_guard>`.  The
derivation carries them into :attr:`StateEquations.guards
<bondgraph.system.StateEquations.guards>` as :class:`DerivedGuard` (the
expression in the model's symbols), and

* :func:`bondgraph.numerics.simulate` raises :class:`~bondgraph.errors.DomainError`
  at the first recorded time point where one is left;
* an exported FMU evaluates them after every internal solver sub-step and
  ends the step with ``fmi2Discard`` / ``fmi3Discard``, naming the guard, its
  value and the time, with the FMU left at the start of the step.

A non-finite value violates every guard.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import sympy as sp

from .errors import DomainError, GraphError

__all__ = ["Guard", "DerivedGuard", "guard_from_dict", "first_violation", "raise_violation",
           "check_param_bounds", "guard_function", "guard_values"]


def _bound(value, what: str, name: str):
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, float)) or math.isnan(value):
        raise GraphError(f"guard {name!r}: {what} {value!r} is not a number")
    return float(value)


@dataclass(frozen=True)
class Guard:
    """The condition ``min <= expression <= max`` (either bound may be None).

    Parameters
    ----------
    name : str
        Name of the guarded quantity (``"V_1"``), used in messages.
    expression : str or sympy.Expr
        The quantity, in the graph's names (states, inputs, parameters, held
        variables, ``t``).
    min, max : float, optional
        Inclusive bounds, in `unit`.
    unit : str
        Unit of the quantity.
    description : str
        What it is (``"chamber volume of muscle 1, eq. (3)"``).
    """

    name: str
    expression: object
    min: float | None = None
    max: float | None = None
    unit: str = ""
    description: str = ""

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name.isidentifier():
            raise GraphError(f"guard name {self.name!r} is not a valid identifier")
        lo, hi = _bound(self.min, "min", self.name), _bound(self.max, "max", self.name)
        if lo is None and hi is None:
            raise GraphError(f"guard {self.name!r} has neither min nor max")
        if lo is not None and hi is not None and lo > hi:
            raise GraphError(f"guard {self.name!r}: min {lo!r} is above max {hi!r}")
        object.__setattr__(self, "min", lo)
        object.__setattr__(self, "max", hi)

    def to_dict(self) -> dict:
        """JSON-ready form (``guard_from_dict`` rebuilds it)."""
        data = {"expression": str(self.expression)}
        data.update({k: getattr(self, k) for k in ("min", "max") if getattr(self, k) is not None})
        data.update({k: getattr(self, k) for k in ("unit", "description") if getattr(self, k)})
        return data

    def condition(self) -> str:
        """The condition as text, e.g. ``"V_1 >= 0 m^3"``."""
        unit = f" {self.unit}" if self.unit and self.unit != "1" else ""
        if self.min is not None and self.max is not None:
            return f"{self.min!r}{unit} <= {self.name} <= {self.max!r}{unit}"
        if self.min is not None:
            return f"{self.name} >= {self.min!r}{unit}"
        return f"{self.name} <= {self.max!r}{unit}"


def guard_from_dict(name: str, data: dict) -> Guard:
    """The :class:`Guard` `name` from its :meth:`Guard.to_dict` form."""
    return Guard(name, data["expression"], data.get("min"), data.get("max"),
                 data.get("unit", ""), data.get("description", ""))


@dataclass(frozen=True)
class DerivedGuard:
    """A :class:`Guard` with its expression in the model's symbols.

    Attributes
    ----------
    guard : Guard
    expr : sympy.Expr
        Free symbols among ``t``, states, inputs, parameters, held variables.
    owner : str
        The element (or ``"graph"``) that declared it.
    """

    guard: Guard
    expr: sp.Expr
    owner: str

    @property
    def name(self) -> str:
        return self.guard.name

    def message(self, value: float, time: float, model: str = "") -> str:
        """The text of a violation: guard, owner, value, condition, time."""
        g = self.guard
        unit = f" {g.unit}" if g.unit and g.unit != "1" else ""
        what = f" ({g.description})" if g.description else ""
        where = f"model {model!r}: " if model else ""
        return (f"{where}{g.name}{what} of {self.owner} = {value:.6g}{unit} leaves its domain "
                f"{g.condition()} at t = {time:.9g} s")


def first_violation(guards, values: np.ndarray, times: np.ndarray):
    """The first (time-ordered) violation in a table of guard values.

    Parameters
    ----------
    guards : sequence of DerivedGuard
    values : ndarray, shape (n_times, n_guards)
        Guard values (units of each guard).
    times : ndarray, shape (n_times,), s

    Returns
    -------
    (int, int) or None
        Row and guard index of the first violation.
    """
    import numpy as np   # lazy: bondgraph imports fast
    if not guards:
        return None
    lo = np.array([-np.inf if g.guard.min is None else g.guard.min for g in guards])
    hi = np.array([np.inf if g.guard.max is None else g.guard.max for g in guards])
    with np.errstate(invalid="ignore"):
        bad = ~(np.isfinite(values) & (values >= lo) & (values <= hi))
    rows = np.flatnonzero(bad.any(axis=1))
    if rows.size == 0:
        return None
    k = int(rows[0])
    return k, int(np.flatnonzero(bad[k])[0])


def raise_violation(guards, values, times, model: str = "") -> None:
    """Raise :class:`DomainError` for the first violation in `values` (see :func:`first_violation`)."""
    hit = first_violation(guards, values, times)
    if hit is None:
        return
    k, j = hit
    g, value, time = guards[j], float(values[k, j]), float(times[k])
    raise DomainError(g.message(value, time, model), variable=g.name, value=value, time=time,
                      owner=g.owner)


def check_param_bounds(eqs, p: np.ndarray) -> None:
    """Raise :class:`~bondgraph.errors.ParameterError` for the first parameter of `eqs`
    (row vector `p`, SI) outside its declared range (``eqs.param_bounds``)."""
    import numpy as np   # lazy: bondgraph imports fast
    from .errors import ParameterError
    if not eqs.param_bounds:
        return
    row = np.asarray(p, dtype=float).reshape(-1, len(eqs.params))
    for j, s in enumerate(eqs.params):
        lo, hi = eqs.param_bounds.get(s.name, (None, None))
        col = row[:, j]
        if (lo is not None and (col < lo).any()) or (hi is not None and (col > hi).any()):
            value = float(col[(col < (lo if lo is not None else -np.inf))
                              | (col > (hi if hi is not None else np.inf))][0])
            unit = eqs.units.get(s.name, "")
            unit = f" {unit}" if unit and unit != "1" else ""
            raise ParameterError(
                f"model {eqs.name!r}: parameter {s.name!r} = {value!r}{unit} is outside its physical "
                f"range [{'unbounded' if lo is None else repr(lo)}, "
                f"{'unbounded' if hi is None else repr(hi)}]{unit}", name=s.name)


def guard_function(eqs):
    """A numpy evaluator of every guard of `eqs`: ``fn(times, X, U, D, p)`` with
    times shape (n,), s; X, U, D shape (n, n_states), (n, n_inputs), (n, n_held);
    p shape (n_params,) -> ndarray, shape (n, n_guards), each in its guard's unit."""
    import numpy as np   # lazy: bondgraph imports fast
    args = (eqs.t, *eqs.states, *eqs.inputs, *eqs.params, *eqs.held)
    raw = sp.lambdify(args, [g.expr for g in eqs.guards], modules="numpy") if eqs.guards else None

    def fn(times, X, U, D, p):
        n = len(times)
        if raw is None:
            return np.empty((n, 0))
        p = np.asarray(p, dtype=float).reshape(-1)
        cols = [np.asarray(times, dtype=float)]
        cols += [X[:, j] for j in range(X.shape[1])] + [U[:, j] for j in range(U.shape[1])]
        cols += [np.full(n, v) for v in p] + [D[:, j] for j in range(D.shape[1])]
        with np.errstate(all="ignore"):
            out = raw(*cols)
        return np.column_stack([np.broadcast_to(np.asarray(v, dtype=float), (n,)) for v in out])
    return fn


def guard_values(eqs, times, X, U, D, p) -> np.ndarray:
    """Every guard of `eqs` along a trajectory (see :func:`guard_function`).

    Returns
    -------
    ndarray, shape (n, n_guards)
    """
    return guard_function(eqs)(times, X, U, D, p)
