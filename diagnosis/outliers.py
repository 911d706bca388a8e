"""Isolated spikes: single samples a sensor glitch put into a recording, which no model explains.

A glitch (an encoder miscount, an ADC spike, a corrupted packet) moves one sample of one output by
many noise standard deviations and leaves its neighbours alone.  Left in, three such samples in a
6 s recording of a dc motor made up most of the held-out error of the motor current, and the
Stribeck friction that explained the rest was answered ``none`` (its share of the held-out error
fell below the 30 % rule).  Sample :math:`k` of output :math:`y` is a spike when

* it stands out of its neighbours' median: :math:`|y_k - \\mathrm{med}(y_{k-1}, y_k, y_{k+1})| >`
  :data:`SPIKE` :math:`\\sigma` (:math:`\\sigma` the output's noise, at least its resolution: a
  step of the signal is no spike, the median follows it);
* and by :data:`LOCAL` times the second differences two samples before and after it, which do
  not involve it (a smooth signal's extremum stands out of its neighbours by its curvature, as
  much as they curve);
* the nominal model does not stand out there by half as much (an output that reads an input
  directly follows that input's own one-sample pulses);
* no recorded input stands out of its neighbours at samples :math:`k-3 \\ldots k` by more than
  :data:`SPIKE` times its own noise (an input's pulse reaching the output late through a delay);
* no state or output of the nominal model changes sign within :data:`_REVERSAL` samples of it (a
  Stribeck friction's breakaway peak, one sample long at 100 Hz, comes where the speed reverses);
* and no other output stands out at :math:`k-1 \\ldots k+1` by more than :data:`ALONE` times its
  noise (a slip of a stick-slip friction moves the speed and the force sensor together; a
  glitch hits one sensor).

An output with more such samples than :data:`MOST` of its samples keeps them all: that many
are the signal's own (a fast physics the samples barely resolve), not glitches.  A spike is
replaced by the mean of its two neighbours, and the report says which samples were (the recording on
disk is unchanged).  ``diagnose(..., spikes="keep")`` keeps them.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

__all__ = ["isolated_spikes", "without_spikes", "spike_notes", "SPIKE", "LOCAL", "ALONE", "MOST"]

#: noise standard deviations by which a sample must stand out of its neighbours' median
SPIKE = 10.0
#: the factor by which it must also stand out of the second differences two samples away
LOCAL = 3.0
#: noise standard deviations by which no other output may stand out at the same time
ALONE = 4.0
#: the largest share of an output's samples that may be spikes (beyond: none are)
MOST = 0.005
#: input samples before a spike (and itself) at which no input may stand out
_INPUT_REACH = 3
#: samples on either side of a spike within which no nominal state or output may change sign
_REVERSAL = 2


def _standing_out(y) -> np.ndarray:
    """:math:`y_k - \\mathrm{med}(y_{k-1}, y_k, y_{k+1})`; 0 at both ends and where not finite."""
    y = np.asarray(y, dtype=float)
    out = np.zeros(y.size)
    if y.size >= 3:
        out[1:-1] = y[1:-1] - np.median(np.stack([y[:-2], y[1:-1], y[2:]]), axis=0)
    out[~np.isfinite(out)] = 0.0
    return out


def _near_reversals(signals, n: int) -> np.ndarray:
    """Samples within :data:`_REVERSAL` of a sign change of any of `signals` (each of length `n`)."""
    near = np.zeros(n, dtype=bool)
    for x in signals:
        x = np.asarray(x, dtype=float)
        if x.shape != (n,):
            continue
        with np.errstate(invalid="ignore"):
            change = np.flatnonzero(np.sign(x[1:]) * np.sign(x[:-1]) < 0)
        for shift in range(-_REVERSAL, _REVERSAL + 2):   # both samples of a change, and R either side
            near[np.clip(change + shift, 0, n - 1)] = True
    return near


def _spiking(y, standing_out, scale: float) -> np.ndarray:
    """Where `y` stands out of its neighbours (`standing_out`, :func:`_standing_out`) by
    :data:`SPIKE` times `scale` and by :data:`LOCAL` times the second differences two samples away."""
    d = np.abs(standing_out)
    return (d > SPIKE * scale) & (d > LOCAL * _curvature_around(y))


def _curvature_around(y) -> np.ndarray:
    r"""The larger :math:`|\Delta^2 y|` at :math:`k - 2` and :math:`k + 2` (inf where either is
    outside the record)."""
    y = np.asarray(y, dtype=float)
    d2 = np.full(y.size, np.inf)
    if y.size >= 3:
        d2[1:-1] = np.abs(y[2:] - 2.0 * y[1:-1] + y[:-2])
    around = np.full(y.size, np.inf)
    if y.size >= 5:
        around[2:-2] = np.maximum(d2[:-4], d2[4:])
    return around


def _resolution(y) -> float:
    """The smallest nonzero step of `y` (its quantisation, for a quantised signal)."""
    steps = np.abs(np.diff(np.asarray(y, dtype=float)))
    steps = steps[np.isfinite(steps) & (steps > 0)]
    return float(steps.min()) if steps.size else 0.0


def isolated_spikes(experiment, predicted: dict, noise: dict, states=None) -> dict:
    """The isolated spikes of each measured output (module docstring).

    Parameters
    ----------
    experiment : Experiment
        The recording, model units.
    predicted : dict str -> ndarray
        The nominal model's outputs on the same samples.
    noise : dict str -> float
        Each output's noise standard deviation (:func:`diagnosis.residuals.noise_sigma`).
    states : ndarray, shape (n, n_states), optional
        The nominal model's states on the same samples.

    Returns
    -------
    dict str -> ndarray of int
        Sample indices by output, only outputs with spikes.
    """
    n = experiment.t.size
    quiet_inputs = np.ones(n, dtype=bool)
    for u in experiment.inputs.values():
        # a command's scale: what its samples stand out by (1.4826 MAD), at least 1e-9 of its span
        # (a command held in steps stands out nowhere but at its pulses)
        u = np.asarray(u, dtype=float)
        d = _standing_out(u)
        scale = max(1.4826 * float(np.median(np.abs(d))), 1e-9 * float(np.ptp(u)), 1e-300)
        loud = _spiking(u, d, scale)
        for lag in range(_INPUT_REACH + 1):            # an input pulse at k - lag reaching the output at k
            quiet_inputs[lag:] &= ~loud[:n - lag]
    calm = ~_near_reversals([*predicted.values(), *(np.asarray(states).T if states is not None else ())], n)
    sigma = {o: max(float(noise.get(o, 0.0)), _resolution(y)) for o, y in experiment.outputs.items()}
    out = {o: _standing_out(y) for o, y in experiment.outputs.items()}
    found = {}
    for o, y in experiment.outputs.items():
        if not sigma[o] > 0:
            continue
        mine = np.abs(out[o])
        theirs = np.abs(_standing_out(predicted[o])) if o in predicted else np.zeros(n)
        spikes = _spiking(y, out[o], sigma[o]) & ~(theirs >= 0.5 * mine) & quiet_inputs & calm
        for other, d in out.items():
            if other != o and sigma[other] > 0:
                loud = np.abs(d) > ALONE * sigma[other]
                spikes &= ~(loud | np.roll(loud, 1) | np.roll(loud, -1))
        index = np.flatnonzero(spikes)
        if 0 < index.size <= MOST * n:
            found[o] = index
    return found


def without_spikes(experiment, spikes: dict):
    """`experiment` with each spike replaced by the mean of its two neighbours."""
    outputs = dict(experiment.outputs)
    for o, index in spikes.items():
        y = np.array(outputs[o], dtype=float)
        y[index] = 0.5 * (y[index - 1] + y[index + 1])
        outputs[o] = y
    return replace(experiment, outputs=outputs)


def spike_notes(experiment, spikes: dict) -> list[str]:
    """One plain-language note per output with spikes: how many, where, by how much."""
    notes = []
    for o, index in spikes.items():
        times = ", ".join(f"{experiment.t[i]:.6g}" for i in index[:5]) + (", ..." if index.size > 5 else "")
        notes.append(f"output {o}: {index.size} isolated spike(s) at t = {times} s, each a single sample "
                     f"standing out of its neighbours by over {SPIKE:g} noise standard deviations where "
                     "the model, the inputs and the other outputs do not, replaced by the mean of its "
                     "neighbours (diagnosis.outliers; spikes='keep' keeps them)")
    return notes
