"""What a kind's features are computed from (:meth:`~diagnosis.kinds.base.Kind.features`).

The feature regression (:mod:`diagnosis.features`) reads, along the run corrected by the
location's estimate, the signals at one junction: its flow ``v`` and effort ``e``, the contents
``q`` of the C elements on it, the pressures and the modulating signals.  Each kind turns them
into its groups of feature columns (:class:`FeatureGroup`), one per variant (a pressure, a C, a
grid value such as a Stribeck velocity); the regression fits each group's columns to the
residual through the junction's linearised response.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import NamedTuple

import numpy as np

__all__ = ["FeatureSignals", "FeatureGroup", "dahl_state", "lagged", "rms", "SIGN_FRACTION"]

#: width of the smoothed sign of the friction features, as a fraction of the RMS flow: a nearly
#: sharp sign (a feature column has no integrator to protect; the friction kinds' feature groups
#: also try 1/3, 3 and 10 times it, and their elements fit their own smoothing,
#: :mod:`diagnosis.kinds.friction_common`)
SIGN_FRACTION = 0.01


class FeatureGroup(NamedTuple):
    """One kind's feature columns at one junction, for one variant."""

    variant: str | None      # what the candidate it matches is keyed by (Candidate.regime or .target)
    detail: str              # the grid value, in words ("v_s = 0.03"), or ""
    names: list              # the columns in words
    columns: np.ndarray      # shape (n, len(names))
    grid: tuple = ()         # the grid value as numbers (an end stop's limits), for a fit's start


@dataclass
class FeatureSignals:
    """The signals at one junction along the corrected run.

    Attributes
    ----------
    t : ndarray, shape (n,)
        Times, s.
    values : dict str -> ndarray
        ``flow``, ``effort``, ``pressure:<expr>``, ``signal:<expr>``, ``content:<C name>``,
        ``c_effort:<C name>`` (the effort the C's law puts on its bond), ``momentum:<I name>``,
        ``travel`` (a 1-junction's flow integrated by the model from 0 at the start), and
        ``estimate`` (the location's estimated extra effort or flow at the junction, where
        there is one).
    one : bool
        A 1-junction (else a 0-junction).
    domain : str
        The junction's domain.
    ambient : float or None
        The effort a leak from a 0-junction flows towards
        (:func:`~diagnosis.catalogue_common.ambient_effort`; None: the leak's own rule).
    """

    t: np.ndarray
    values: dict
    one: bool
    domain: str
    ambient: float | None = None

    @cached_property
    def v(self) -> np.ndarray:
        """The junction's flow."""
        return np.asarray(self.values["flow"], float)

    @cached_property
    def v_rms(self) -> float:
        return rms(self.v)

    @cached_property
    def sign(self) -> np.ndarray:
        """A nearly sharp sign of the flow (:data:`SIGN_FRACTION`)."""
        return self.sign_at(SIGN_FRACTION)

    def sign_at(self, fraction: float) -> np.ndarray:
        """The sign of the flow smoothed over `fraction` of the RMS flow."""
        return np.tanh(self.v / (fraction * self.v_rms))

    @cached_property
    def dt(self) -> float:
        return float(np.median(np.diff(self.t))) if self.t.size > 1 else 1.0

    @cached_property
    def span(self) -> float:
        return float(self.t[-1] - self.t[0]) if self.t.size > 1 else 1.0

    @cached_property
    def travel(self) -> np.ndarray:
        """The integral of the flow from 0 at the first sample: the model's own (``travel``, where
        read; :func:`diagnosis.features._with_travel`), else trapezoids of the sampled flow."""
        if "travel" in self.values:
            return np.asarray(self.values["travel"], float)
        return np.concatenate([[0.0], np.cumsum(0.5 * (self.v[1:] + self.v[:-1]) * np.diff(self.t))])

    @cached_property
    def displacement(self) -> np.ndarray:
        """The integral of the flow (:attr:`travel`), mean removed."""
        return self.travel - self.travel.mean()

    def labelled(self, prefix: str) -> dict:
        """``{label: values}`` of the signals keyed ``prefix:label`` that move."""
        return {k.split(":", 1)[1]: np.asarray(x, float) for k, x in self.values.items()
                if k.startswith(f"{prefix}:") and np.ptp(x) > 0}


def dahl_state(v, t, alpha, travel=None):
    """The normalised Dahl state :math:`\\dot z = \\alpha (v - |v| z)`, z(0) = 0, v held over
    each interval (exact per interval): the Dahl friction is :math:`F_h z`.  With `travel` (the
    flow's integral at the samples), each interval moves z by its own travel instead,
    :math:`z \\to \\mathrm{sign}(\\Delta\\theta) + (z - \\mathrm{sign}(\\Delta\\theta))
    e^{-\\alpha |\\Delta\\theta|}` (exact where the flow keeps its sign over the interval):
    a flow sampled where it jumps (a held input's step) overstates the interval's travel.

    Parameters
    ----------
    v : ndarray, shape (n,)
        Flow (velocity, m/s or rad/s).
    t : ndarray, shape (n,)
        Times, s.
    alpha : float
        :math:`\\sigma / F_h`, per unit of displacement (1/m, 1/rad).

    Examples
    --------
    >>> t = np.linspace(0.0, 1.0, 101)
    >>> round(float(dahl_state(np.ones(101), t, 50.0)[-1]), 6)     # steady sliding: z -> 1
    1.0
    """
    v, t = np.asarray(v, float), np.asarray(t, float)
    z = np.zeros(v.size)
    step = v[:-1] * np.diff(t) if travel is None else np.diff(np.asarray(travel, float))
    decay = np.exp(-alpha * np.abs(step))
    target = np.sign(step)
    for k in range(v.size - 1):
        z[k + 1] = target[k] + (z[k] - target[k]) * decay[k]
    return z


def lagged(m, t, tau, start=None):
    """First-order lag (time constant `tau`, s) of a held signal, started at `start` (default: its
    first value)."""
    y = np.empty_like(m, dtype=float)
    y[0] = m[0] if start is None else start
    decay = np.exp(-np.diff(t) / tau)
    for k in range(m.size - 1):
        y[k + 1] = m[k] + (y[k] - m[k]) * decay[k]
    return y


def rms(x) -> float:
    """Root mean square, 1 for an empty, zero or non-finite signal (a scale)."""
    x = np.asarray(x, float)
    value = float(np.sqrt(np.mean(x ** 2))) if x.size else 0.0
    return value if value > 0 and np.isfinite(value) else 1.0
