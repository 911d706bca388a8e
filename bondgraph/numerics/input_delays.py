"""Delayed inputs on sampled records: :math:`u_d(t) = u(t - T)`, exact on zero-order-hold tables.

A delayed input (:class:`~bondgraph.elements.base.InputDelay`) is realised on the source's
samples, not by states: a state realisation (a lag, a Pade chain) reads the command of the
previous interval at a sample, so an output that reads the input directly (a force ``p A``, a
velocity ``(x - x_s)/tau``) is a sample late, whatever the delay.  A recorded command is a
zero-order-hold table, and so is its delayed copy: its steps move by :math:`T`.  A delay of whole
samples keeps them on the sample grid; a fraction of a sample puts them inside the intervals, so
the grid the model is integrated on gets those instants too (:func:`inputs_on_grid`): the state
then sees each value for exactly as long as the delayed command holds it, and moves smoothly with
:math:`T` (a fit can find it).  Before the record the source is at its ``before`` value, which
a parameter may hold (:func:`before_values`): where the source rested before a record is often
unknown, and a fit can find it as it finds :math:`T`.
"""
from __future__ import annotations

import numpy as np

from ..errors import ArgumentError

__all__ = ["delayed_samples", "delay_values", "before_values", "inputs_on_grid"]

#: a step this close to a grid time (as a share of the smallest sample interval) is on it
_ON_GRID = 1e-9


def _tolerance(t) -> float:
    """How close to a sample time a step counts as on it, s (:data:`_ON_GRID` of the shortest interval)."""
    return _ON_GRID * (float(np.min(np.diff(t))) if t.size > 1 else 1.0)


def delayed_samples(t, values, delay: float, before: float | None = None, at=None) -> np.ndarray:
    """The zero-order-hold table (`t`, `values`) delayed by `delay` seconds, at the times `at`.

    Parameters
    ----------
    t : ndarray, shape (n,)
        Strictly increasing sample times, s.
    values : ndarray, shape (n,)
        The source's samples, each held until the next sample.
    delay : float
        Delay, s (>= 0).
    before : float, optional
        The source's value before ``t[0]``; default its first sample.
    at : ndarray, optional
        Times to evaluate at, s; default `t`.

    Returns
    -------
    ndarray

    Examples
    --------
    Two samples late the record shifts by two; half a sample late, the sample times still see the
    previous value (the step comes half an interval after each of them):

    >>> t = np.arange(5.0)
    >>> delayed_samples(t, np.array([1.0, 2, 3, 4, 5]), 2.0, 0.0).tolist()
    [0.0, 0.0, 1.0, 2.0, 3.0]
    >>> delayed_samples(t, np.array([1.0, 2, 3, 4, 5]), 0.5, 0.0).tolist()
    [0.0, 1.0, 2.0, 3.0, 4.0]
    """
    t = np.asarray(t, dtype=float)
    values = np.asarray(values, dtype=float)
    at = t if at is None else np.asarray(at, dtype=float)
    before = float(values[0]) if before is None else float(before)
    if not delay >= 0 or not np.isfinite(delay):
        raise ArgumentError(f"a delay must be a finite number of seconds >= 0; found {delay!r}")
    tol = _tolerance(t)
    k = np.searchsorted(t, at - delay + tol, side="right") - 1
    return np.where(k >= 0, values[np.clip(k, 0, None)], before)


def delay_values(eqs, params: dict | None = None) -> dict:
    """Delayed input name -> its delay (s) under `params` (name -> value; others at their defaults);
    a negative or non-finite delay is an :class:`~bondgraph.errors.ArgumentError` naming it."""
    params = params or {}
    delays = {name: float(params.get(d.time, eqs.param_values[d.time])) for name, d in eqs.input_delays.items()}
    for name, value in delays.items():
        if not (np.isfinite(value) and value >= 0):
            raise ArgumentError(f"input {name!r} of model {eqs.name!r}: its delay {eqs.input_delays[name].time!r} "
                                f"is {value!r} s; a delay is a finite number of seconds >= 0",
                                name=eqs.input_delays[name].time)
    return delays


def before_values(eqs, params: dict | None = None) -> dict:
    """Delayed input name -> its value before the record under `params` (name -> value; others at
    their defaults): the number given, its parameter's value, or None (the source's first value)."""
    params = params or {}
    out = {}
    for name, d in eqs.input_delays.items():
        before = d.before
        if isinstance(before, str):
            before = float(params.get(before, eqs.param_values[before]))
            if not np.isfinite(before):
                raise ArgumentError(f"input {name!r} of model {eqs.name!r}: its value before the run "
                                    f"{d.before!r} is {before!r}; expected a finite number", name=d.before)
        out[name] = before
    return out


def inputs_on_grid(eqs, t, U, delays: dict, befores: dict | None = None, *, past=None):
    """The grid a run on the samples `t` is integrated on, and its inputs.

    Parameters
    ----------
    eqs : StateEquations
    t : ndarray, shape (n,)
        Sample times, s.
    U : ndarray, shape (n, n_inputs)
        Inputs at the samples, model input order, each held over its interval; the delayed
        inputs' columns are ignored.
    delays : dict str -> float
        Delay of each delayed input, s (:func:`delay_values`).
    befores : dict str -> float or None, optional
        Each delayed input's value before the record (:func:`before_values`); default the model's.
    past : tuple (t_past, U_past), optional
        The inputs recorded before ``t[0]`` (times, s, and a matrix like `U`), where `t` is a part
        of a longer record: a delay that reaches back before ``t[0]`` reads them, and the value
        before the record only before ``t_past[0]``.

    Returns
    -------
    (grid, U_grid, at)
        `grid` holds `t` and every step of a delayed input that falls between two samples;
        `U_grid` the inputs held over each of its intervals (the undelayed ones as recorded, the
        delayed ones their source `T` late); ``grid[at] == t``.  Without delayed inputs, or with
        whole-sample delays only, `grid` is `t`.
    """
    t = np.asarray(t, dtype=float)
    if not eqs.input_delays:
        return t, U, np.arange(t.size)
    t_all, U_all = t, np.asarray(U, float)
    if past is not None and np.size(past[0]):
        # only the past a delay reaches back into: the sample held at t[0] - (the longest delay) on
        t_past = np.asarray(past[0], float)
        keep = max(int(np.searchsorted(t_past, t[0] - max(delays.values()), side="right")) - 1, 0)
        t_all = np.concatenate([t_past[keep:], t])
        U_all = np.concatenate([np.asarray(past[1], float).reshape(-1, U_all.shape[1])[keep:], U_all])
    tol = _tolerance(t)
    extra = np.concatenate([t_all + delays[name] for name in eqs.input_delays])
    extra = extra[(extra > t[0]) & (extra < t[-1])]
    # steps that fall on (or a rounding error from) a sample stay on it
    near = np.searchsorted(t, extra)
    off = np.ones(extra.size, dtype=bool)
    for j in (near - 1, near):
        ok = (j >= 0) & (j < t.size)
        off[ok] &= np.abs(extra[ok] - t[j[ok]]) > tol
    grid = np.union1d(t, extra[off])
    at = np.searchsorted(grid, t)
    column = {name: j for j, name in enumerate(eqs.input_names)}
    parent = np.searchsorted(t, grid + tol, side="right") - 1      # the sample each grid time holds
    U_grid = np.ascontiguousarray(np.asarray(U, dtype=float)[np.clip(parent, 0, None)])
    befores = before_values(eqs) if befores is None else befores
    for name, d in eqs.input_delays.items():
        U_grid[:, column[name]] = delayed_samples(t_all, U_all[:, column[d.source]], delays[name], befores[name],
                                                  at=grid)
    return grid, np.ascontiguousarray(U_grid), at
