"""Delayed inputs on sampled records: :math:`u_d(t_k) = u(t_k - T)`.

A delayed input (:class:`~bondgraph.elements.base.InputDelay`) is realised on the source's
samples, not by states: a state realisation (a lag, a Pade chain) reads the command of the
previous interval at a sample, so an output that reads the input directly (a force ``p A``, a
velocity ``(x - x_s)/tau``) is a sample late, whatever the delay.  Between samples the source is
interpolated linearly, so the delayed values move smoothly with :math:`T` (a fit can find it) and
a delay of whole samples shifts the record exactly.  Before the record the source is at its
``before`` value, taken to hold one sample interval before the first sample.
"""
from __future__ import annotations

import numpy as np

from ..errors import ArgumentError

__all__ = ["delayed_samples", "fill_delayed_inputs", "delay_values"]


def delayed_samples(t, values, delay: float, before: float | None = None) -> np.ndarray:
    """`values` (sampled at `t`) delayed by `delay` seconds, at the times `t`.

    Parameters
    ----------
    t : ndarray, shape (n,)
        Strictly increasing sample times, s.
    values : ndarray, shape (n,)
        The source's samples.
    delay : float
        Delay, s (>= 0).
    before : float, optional
        The source's value before ``t[0]`` (one sample interval before it and earlier); default
        its first sample.

    Returns
    -------
    ndarray, shape (n,)

    Examples
    --------
    A delay of two samples shifts the record by two; half a sample blends neighbours:

    >>> t = np.arange(5.0)
    >>> delayed_samples(t, np.array([1.0, 2, 3, 4, 5]), 2.0, 0.0).tolist()
    [0.0, 0.0, 1.0, 2.0, 3.0]
    >>> delayed_samples(t, np.array([1.0, 2, 3, 4, 5]), 0.5, 0.0).tolist()
    [0.5, 1.5, 2.5, 3.5, 4.5]
    """
    t = np.asarray(t, dtype=float)
    values = np.asarray(values, dtype=float)
    before = float(values[0]) if before is None else float(before)
    if not delay >= 0 or not np.isfinite(delay):
        raise ArgumentError(f"a delay must be a finite number of seconds >= 0; found {delay!r}")
    if t.size < 2:
        return np.full(t.shape, before) if delay > 0 else values.copy()
    grid = np.concatenate([[t[0] - (t[1] - t[0])], t])
    return np.interp(t - delay, grid, np.concatenate([[before], values]), left=before)


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


def fill_delayed_inputs(eqs, t, U, delays: dict) -> np.ndarray:
    """The input matrix `U` (model input order, shape (n, n_inputs)) with every delayed input's
    column computed from its source's column (:func:`delayed_samples`); `delays` from
    :func:`delay_values`.  `U` itself is left alone."""
    if not eqs.input_delays:
        return U
    U = np.array(U, dtype=float, copy=True)
    column = {name: j for j, name in enumerate(eqs.input_names)}
    for name, d in eqs.input_delays.items():
        U[:, column[name]] = delayed_samples(t, U[:, column[d.source]], delays[name], d.before)
    return np.ascontiguousarray(U)
