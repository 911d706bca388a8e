"""Recordings at other rates and lengths (``python -m diagnosis.benchmark --sampling F``).

Each benchmark plant records at one rate and for one duration (:class:`~.plant.TruthPlant`), chosen
to suit it; a rig's recording is whatever its logger gave.  With ``--sampling F`` each case's sample
rate is scaled by a factor drawn log-uniformly in :math:`[1/F, F]` and its duration by one in
:math:`[1/\\sqrt F, \\sqrt F]`, both from the case's own seed (its other draws stay what they were
without it).  The diagnosis is told nothing of it: a rate or a length that one of its steps assumed
shows up as a miss.  The truth's integration follows the rate by itself
(:func:`diagnosis.benchmark.simulate.simulate_truth` refines its sub-steps to the plant's stiffness).
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..errors import BenchmarkError

__all__ = ["resampled"]


def resampled(plant, seed: int, spread: float):
    """``(plant, sampling)``: `plant` with its rate and duration scaled (module docstring) and what
    was drawn (``rate`` and ``duration``, Hz and s, with their factors); ``(plant, {})`` for
    `spread` 1.

    Examples
    --------
    >>> @dataclasses.dataclass
    ... class P:
    ...     rate: float = 100.0
    ...     duration: float = 20.0
    >>> p, drawn = resampled(P(), 5, 2.0)
    >>> 50.0 <= p.rate <= 200.0 and 20 / 2 ** 0.5 <= p.duration <= 20 * 2 ** 0.5
    True
    >>> resampled(P(), 5, 1.0)[1]
    {}
    """
    if not spread >= 1.0 or not math.isfinite(spread):
        raise BenchmarkError(f"--sampling must be a factor of at least 1, got {spread}")
    if spread == 1.0:
        return plant, {}
    rng = np.random.default_rng([int(seed), 13])
    rate_factor = math.exp(rng.uniform(-1.0, 1.0) * math.log(spread))
    duration_factor = math.exp(rng.uniform(-0.5, 0.5) * math.log(spread))
    out = dataclasses.replace(plant, rate=plant.rate * rate_factor, duration=plant.duration * duration_factor)
    return out, {"rate": out.rate, "rate_factor": rate_factor,
                 "duration": out.duration, "duration_factor": duration_factor}
