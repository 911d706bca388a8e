"""Frequency-domain analysis of the ``exo-lqi`` loops, written without
python-control (which the tests use as the cross-check): stability margins of
the loop broken at the plant input (Figs. 13-14 of [1]_) and the bandwidth of
trunk velocity -> estimated body torque (Fig. 15).

Definitions (negative feedback, loop gain :math:`L(j\\omega)`):

- gain crossover :math:`|L(j\\omega_{gc})| = 1`; phase margin
  :math:`PM = 180° + \\angle L(j\\omega_{gc})` (wrapped to (-180°, 180°]);
- phase crossover :math:`\\operatorname{Im} L(j\\omega_{pc}) = 0,\\ \\operatorname{Re} L < 0`;
  gain margin :math:`GM = -1 / \\operatorname{Re} L(j\\omega_{pc})`;
- delay margin :math:`PM / \\omega_{gc}` (PM in rad), the smallest over the
  gain crossovers with positive PM.

Where there are several crossovers the margin nearest the critical point is
reported (GM: smallest :math:`|\\log GM|`; PM: smallest :math:`|PM|`), as
python-control's ``stability_margins`` does.

References
----------
.. [1] Exoskeleton bond graph / Kalman observer paper,
   seed 004 (``docs/references.md``), Section 5.2, Figs. 13-15.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq, minimize_scalar

__all__ = ["freqresp", "Margins", "margins", "Bandwidth", "band_limits"]

#: Frequency grid of the crossover search, rad/s (the loop's poles span 1e-1 .. 3e6 rad/s).
GRID = np.logspace(-3, 7, 20001)


def freqresp(A, B, C, D, w, *, dt: float | None = None) -> np.ndarray:
    """:math:`C (s I - A)^{-1} B + D` of a SISO system at `w` (rad/s), shape (len(w),), complex.

    ``s = j w`` for a continuous system; ``z = exp(j w dt)`` for a discrete
    one of period `dt` (s).  Solved through the eigen-decomposition of ``A``
    (diagonalisable here), one batched solve otherwise.
    """
    A, B, C, D = (np.asarray(m, dtype=float) for m in (A, B, C, D))
    w = np.atleast_1d(np.asarray(w, dtype=float))
    s = 1j * w if dt is None else np.exp(1j * w * dt)
    lam, V = np.linalg.eig(A)
    if np.linalg.cond(V) < 1e8:
        cb = (C @ V).ravel() * np.linalg.solve(V, B).ravel()     # residues c_i b_i
        return (cb[None, :] / (s[:, None] - lam[None, :])).sum(axis=1) + D[0, 0]
    M = s[:, None, None] * np.eye(A.shape[0]) - A            # one batched solve (Jordan blocks)
    return (C @ np.linalg.solve(M, np.broadcast_to(B, (s.size,) + B.shape)))[:, 0, 0] + D[0, 0]


def _roots(fun, w):
    """Refined zeros of the real function `fun` of log10(w) between grid points where it changes sign."""
    lw = np.log10(w)
    v = fun(lw)
    idx = np.nonzero(np.sign(v[:-1]) * np.sign(v[1:]) < 0)[0]
    def scalar(x):
        return float(np.asarray(fun(np.array([x]))).ravel()[0])
    return np.array([10.0 ** brentq(scalar, lw[i], lw[i + 1], xtol=1e-13) for i in idx])


@dataclass(frozen=True)
class Margins:
    """Stability margins of a loop gain.

    Attributes
    ----------
    gain : float
        Gain margin, absolute (``inf`` without phase crossover).
    gain_db : float, dB
    phase_deg : float, deg
    delay_s : float, s
    w_pc, w_gc : float, rad/s
        Phase and gain crossover frequencies of the reported margins.
    """

    gain: float
    gain_db: float
    phase_deg: float
    delay_s: float
    w_pc: float
    w_gc: float


def margins(A, B, C, D, *, dt: float | None = None, w=GRID) -> Margins:
    """Gain, phase and delay margins of the SISO loop gain ``(A, B, C, D)`` (module docstring).

    Parameters
    ----------
    A, B, C, D : array_like
        Loop gain, continuous or (with `dt`) discrete.
    dt : float, s, optional
        Sampling period of a discrete loop (frequencies up to the Nyquist frequency ``pi / dt``).
    w : ndarray, rad/s
        Search grid.
    """
    if dt is not None:
        w = w[w < np.pi / dt]

    def L(lw):
        return freqresp(A, B, C, D, 10.0 ** np.asarray(lw), dt=dt)

    w_gc = _roots(lambda lw: np.log(np.abs(L(lw))), w)
    w_pc = [wp for wp in _roots(lambda lw: L(lw).imag, w) if L(np.log10(wp))[0].real < 0]
    if w_pc:
        gms = np.array([-1.0 / L(np.log10(wp))[0].real for wp in w_pc])
        i = int(np.argmin(np.abs(np.log(gms))))
        gain, wpc = float(gms[i]), float(w_pc[i])
    else:
        gain, wpc = float("inf"), float("nan")
    if w_gc.size:
        pms = np.degrees(np.angle(L(np.log10(w_gc)))) + 180.0
        pms = (pms + 180.0) % 360.0 - 180.0                 # wrap to [-180, 180)
        i = int(np.argmin(np.abs(pms)))
        phase, wgc = float(pms[i]), float(w_gc[i])
        pos = pms > 0
        delay = float(np.min(np.radians(pms[pos]) / w_gc[pos])) if pos.any() else 0.0
    else:
        phase, wgc, delay = float("inf"), float("nan"), float("inf")
    return Margins(gain, float(20.0 * np.log10(gain)), phase, delay, wpc, wgc)


@dataclass(frozen=True)
class Bandwidth:
    """Band limits of a band-pass magnitude response.

    Attributes
    ----------
    dc_gain : float
        ``|G(0)|`` (0 for the LQI with double integral action).
    peak_gain : float
        Largest ``|G(j w)|``.
    peak_hz : float, Hz
    upper_hz, lower_hz : float, Hz
        First frequency above (below) the peak where ``|G|`` drops 3 dB under the peak.
    """

    dc_gain: float
    peak_gain: float
    peak_hz: float
    upper_hz: float
    lower_hz: float


def band_limits(A, B, C, D, *, w=GRID) -> Bandwidth:
    """-3 dB limits around the peak of the SISO response ``(A, B, C, D)``.

    The paper's definition (first frequency 3 dB below the DC value) needs a
    non-zero DC gain; trunk velocity -> body torque has a zero at ``s = 0``
    under double integral action, so the peak is the reference instead.
    """
    def gain(lw):
        return float(np.abs(freqresp(A, B, C, D, [10.0 ** lw])[0]))

    i = int(np.argmax(np.abs(freqresp(A, B, C, D, w))))
    lo, hi = np.log10(w[max(i - 1, 0)]), np.log10(w[min(i + 1, w.size - 1)])
    wpk = 10.0 ** minimize_scalar(lambda lw: -gain(lw), bounds=(lo, hi), method="bounded",
                                  options={"xatol": 1e-10}).x
    peak = gain(np.log10(wpk))

    def drop(lw):
        return np.log(np.abs(freqresp(A, B, C, D, 10.0 ** np.asarray(lw))) * np.sqrt(2.0) / peak)
    above = _roots(drop, w[w > wpk])
    below = _roots(drop, w[w < wpk])
    dc = float(abs(freqresp(A, B, C, D, [0.0])[0]))
    hz = 1.0 / (2.0 * np.pi)
    return Bandwidth(dc, peak, wpk * hz, float(above[0]) * hz if above.size else float("inf"),
                     float(below[-1]) * hz if below.size else 0.0)
