"""Graph location for a nominal model that diverges on the recording (multiple shooting).

:func:`diagnosis.graph_location.locate_on_graph` linearises along one nominal run of the
training part, which a diverging nominal does not have.  Here the training part is cut into
:data:`WINDOWS` windows; each restarts from a state fitted to its first samples
(:func:`diagnosis.initial_state.fit_state`, pulled towards the model's default state) and ends
before the nominal leaves the finite numbers from there (at 90 % of the time it ran finite);
every place is located on each window by ``locate_on_graph`` and its scores are pooled:

.. math:: \\text{explained} = \\sum_k E_{0,k}\\,\\text{explained}_k \\Big/ \\sum_k E_{0,k},

:math:`E_{0,k}` the window's noise-weighted nominal residual energy.  Each window's correction
is its own (the junction's piecewise-linear effort, an input's or output's correction): a
simplification of one joint problem over all windows, which would share the input and output
corrections across them.  The estimates are NaN outside the windows.
"""
from __future__ import annotations

import numpy as np

from .errors import BondcosimError

__all__ = ["locate_on_segments", "WINDOWS"]

#: windows the training part is cut into
WINDOWS = 5
#: fewest samples of a window (graph location needs a few knots' worth)
_MIN_SAMPLES = 40


def _finite_window(sim, train, a, b, noise):
    """``(stop, state, energy)`` of the window starting at sample `a`: its state fitted to its first
    quarter, its end cut where the nominal stays finite from there; None when too short."""
    from .initial_state import fit_state
    head = train.samples(a, a + max(10, (b - a) // 4))
    prior = sim.initial_state(None)
    scale = np.where(np.abs(prior) > 0, np.abs(prior), 1.0)
    x = fit_state(sim.on(head), {o: np.asarray(v, float) for o, v in head.outputs.items()}, noise, prior, scale)
    if x is None:
        return None
    for _ in range(8):
        if b - a < _MIN_SAMPLES:
            return None
        win = train.samples(a, b)
        try:
            out = sim.on(win)(None, x)
        except BondcosimError as exc:
            t_div = getattr(exc, "time", None)
            if t_div is None:
                return None
            stop = float(win.t[0]) + 0.9 * (float(t_div) - float(win.t[0]))
            b = a + int(np.count_nonzero(win.t <= stop))
            continue
        energy = sum(float(np.sum((np.asarray(win.outputs[o], float) - out[o]) ** 2)) / max(noise.get(o, 0.0), 1e-300) ** 2
                     for o in out)
        return b, x, energy
    return None


def locate_on_segments(model, train, noise: dict, *, length: int | None = None, progress=False) -> list:
    """Places ranked by their pooled share over restarted windows of the training part (see the
    module docstring).

    Parameters
    ----------
    model : BondGraph
        The nominal model.
    train : Experiment
        The training part.
    noise : dict str -> float
        Noise standard deviation of each output (model units).
    length : int, optional
        Samples per window (default: the training part in :data:`WINDOWS`).  A nominal whose
        unstable mode made the segment judge is located on windows as long as its segments: within
        them the nominal restarted from the data stays near it, so a linearisation along its run
        means something.
    progress : bool

    Returns
    -------
    list of PlaceScore
        Best first; empty when no window runs finite.
    """
    from .graph_location import PlaceScore, locate_on_graph
    from .residuals import OutputSimulator

    sim = OutputSimulator(model, train)
    n = train.t.size
    length = max(_MIN_SAMPLES, n // WINDOWS if length is None else int(length))
    pooled, energy_sum = {}, 0.0
    for a in range(0, n - _MIN_SAMPLES + 1, length):
        found = _finite_window(sim, train, a, min(n, a + length), noise)
        if found is None:
            continue
        b, x, e0 = found
        try:
            scores = locate_on_graph(model, train.samples(a, b), progress=progress,
                                     x0=dict(zip(sim.model.state_names, map(float, x))))
        except (BondcosimError, np.linalg.LinAlgError, FloatingPointError):
            continue
        energy_sum += e0
        for s in scores:
            key = (s.place.kind, s.place.name)
            slot = pooled.setdefault(key, PlaceScore(s.place, 0.0, np.full(n, np.nan), s.unit, s.bond, 0.0))
            slot.explained += e0 * s.explained
            slot.dof += s.dof
            slot.estimate[a:b] = s.estimate
    if energy_sum <= 0:
        return []
    for s in pooled.values():
        s.explained /= energy_sum
    return sorted(pooled.values(), key=lambda s: -s.explained)
