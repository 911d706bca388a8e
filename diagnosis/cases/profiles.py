"""Seeded excitation profiles for the test recordings (values in the model's SI units).

Every profile is piecewise constant on the sample grid (a command written by a
digital controller, held by its DAC), so the zero-order-hold table the
diagnosis builds from the recorded column is exactly what the truth model saw.
All randomness comes from the ``rng`` argument (``numpy.random.Generator``).
"""
from __future__ import annotations

import numpy as np

__all__ = ["held_levels", "staircase", "prbs", "dac"]


def held_levels(t, rng, *, low: float, high: float, hold: tuple[float, float]) -> np.ndarray:
    """Random levels, uniform in [`low`, `high`], each held for a random time in `hold` (s).

    Parameters
    ----------
    t : ndarray, shape (n,), s
        Sample times (increasing, starting at 0).
    rng : numpy.random.Generator
    low, high : float
        Level range (model unit).
    hold : (float, float), s
        Shortest and longest hold time.
    """
    t = np.asarray(t, dtype=float)
    out = np.empty_like(t)
    start = 0
    while start < len(t):
        stop = np.searchsorted(t, t[start] + rng.uniform(*hold))
        out[start:max(stop, start + 1)] = rng.uniform(low, high)
        start = max(stop, start + 1)
    return out


def staircase(t, *, amplitude: float, step_time: float, n_levels: int) -> np.ndarray:
    """A slow triangle made of `n_levels` steps per half period (a stepped ramp).

    Goes 0 -> +amplitude -> -amplitude -> +amplitude ..., changing level every
    `step_time` seconds: constant-velocity plateaus at many speeds, both signs.
    """
    t = np.asarray(t, dtype=float)
    k = np.floor(t / step_time).astype(int)
    period = 4 * n_levels
    phase = (k + n_levels) % period           # start at 0, rising
    tri = np.where(phase < 2 * n_levels, phase - n_levels, 3 * n_levels - phase)
    return amplitude * tri / n_levels


def prbs(t, rng, *, low: float, high: float, bit_time: float) -> np.ndarray:
    """Pseudo-random binary sequence between `low` and `high`, one random bit per `bit_time` s."""
    t = np.asarray(t, dtype=float)
    bits = rng.integers(0, 2, size=int(np.ceil(t[-1] / bit_time)) + 1)
    return np.where(bits[np.floor(t / bit_time).astype(int)] == 1, high, low)


def dac(values, quantum: float, *, low: float = -np.inf, high: float = np.inf) -> np.ndarray:
    """Round a command to the DAC resolution `quantum` and clip it to the DAC range."""
    return np.clip(np.round(np.asarray(values, dtype=float) / quantum) * quantum, low, high)
