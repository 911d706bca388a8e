"""The discrete PI controller of the UKF-based sensor-less PAM control of [1]_
(Section IV.C): :class:`DiscretePI`.

Equation (unnumbered, Section IV.C of [1]_), one scalar state ``x`` and two
valve voltages ``u = [u1, u2]`` (V) driving the antagonistic PAMs in
opposite directions around the bias ``beta``:

.. math::

    x_{k+1} = x_k + e_k, \\qquad u_k = C x_k + D e_k + \\beta, \\qquad
    C = \\pm\\begin{bmatrix} c \\\\ -c \\end{bmatrix},\\;
    D = \\begin{bmatrix} T_P \\\\ -T_P \\end{bmatrix},\\;
    \\beta = \\begin{bmatrix} 5.5 \\\\ 5.5 \\end{bmatrix}

with the feedback error :math:`e = \\bar{\\cdot} - \\hat{\\cdot}`, reference
minus UKF estimate (Fig. 13).  With :math:`\\tau = r\\cos\\psi\\,(F_1 - F_2)`
(eq. (9)), raising ``u1`` and lowering ``u2`` raises the torque and the angle,
so this sign is negative feedback.  Note that ``u_k`` uses ``x_k``, the sum of
the errors *before* sample ``k``: the integral term lags one sample.

Reading of ``C``
----------------
The text prints :math:`c = T_I / T_{stp}` and calls :math:`T_I` "an integral
gain".  Since ``x`` is a plain sum of errors, :math:`c\\,x` approximates
:math:`T_I \\int e\\,dt` only with :math:`c = T_I T_{stp}`; the printed
:math:`T_I / T_{stp}` is :math:`10^6` times larger at :math:`T_{stp} = 1` ms
(a 0.01 rad error held for one sample would move the valves by 15.5 V, beyond
the 0-10 V range).  ``reading="gain"`` (default) uses
:math:`c = T_I T_{stp}`; ``reading="printed"`` uses the formula as printed.

Gains and limits
----------------
:data:`PAPER_GAINS`: :math:`T_P = 5.45`, :math:`T_I = 1.55` (angle loop) and
:math:`T_P = 7.45`, :math:`T_I = 4.75` (torque loop), found by trial and error;
:math:`\\beta = 5.5` V from the valve specification; :math:`T_{stp} = 1` ms.
The paper does not state the unit of ``e``; rad for the angle and N m for the
torque are the SI reading (the errors it reports are in degrees, which would
make the angle gains 57 times more aggressive).  The valve inputs lie in
:math:`\\mathcal{U} = [0, 10]^2` V (Section II.B), so the output is clipped to
``u_limits`` (default (0, 10) V).  **The paper describes no anti-windup**; by
default the integrator runs on while the output is clipped, as the printed
equations do.  ``anti_windup=True`` adds conditional integration (the error
is not added while an output is clipped and the error would push it further),
which is our addition, not the paper's.

References
----------
.. [1] T. Shin and K. Kogiso, "Detailed dynamic model of antagonistic PAM
   system and its experimental validation: sensor-less angle and torque
   control with UKF"; seed 000 (``docs/references.md``).
"""
from __future__ import annotations

from typing import Literal

import numpy as np

from estimators.errors import EstimatorError

__all__ = ["DiscretePI", "PAPER_GAINS"]

#: (T_P, T_I) of Section IV.C of [1]_, per loop.
PAPER_GAINS = {"angle": (5.45, 1.55), "torque": (7.45, 4.75)}


class DiscretePI:
    """The PI of [1]_, Section IV.C: ``u = step(reference, measurement)`` with ``u = [u1, u2]`` in V.

    Parameters
    ----------
    TP : float
        Proportional gain (V per unit of the error).
    TI : float
        Integral gain (V per unit of the error per s).
    Tstp : float, s
        Sampling period (1 ms in [1]_).
    beta : float, V
        Bias of both valve voltages (5.5 V in [1]_).
    reading : {"gain", "printed"}
        ``C = +-TI*Tstp`` (default) or ``C = +-TI/Tstp`` as printed (module docstring).
    u_limits : (float, float) or None, V
        Output clipping (the paper's input set [0, 10] V); None for none.
    anti_windup : bool
        Conditional integration while clipped (not in the paper; default False).

    Attributes
    ----------
    x : float
        Controller state: sum of past errors (unit of the error).
    C, D : ndarray, shape (2,)
    beta : ndarray, shape (2,)

    Examples
    --------
    >>> pi = DiscretePI(5.45, 1.55)
    >>> pi.step(0.1, 0.0).round(6).tolist()       # u0 = D e0 + beta
    [6.045, 4.955]
    >>> pi.step(0.1, 0.0).round(6).tolist()       # + C x1, x1 = e0 = 0.1
    [6.045155, 4.954845]
    """

    def __init__(self, TP: float, TI: float, *, Tstp: float = 1e-3, beta: float = 5.5,
                 reading: Literal["gain", "printed"] = "gain",
                 u_limits: tuple[float, float] | None = (0.0, 10.0), anti_windup: bool = False):
        vals = {}
        for name, v in (("TP", TP), ("TI", TI), ("Tstp", Tstp), ("beta", beta)):
            try:
                vals[name] = float(v)
            except (TypeError, ValueError):
                raise EstimatorError(f"DiscretePI: {name} must be a real number, got {v!r}", name=name) from None
            if not np.isfinite(vals[name]):
                raise EstimatorError(f"DiscretePI: {name} must be finite, got {v!r}", name=name)
        if vals["Tstp"] <= 0:
            raise EstimatorError(f"DiscretePI: Tstp must be > 0 s, got {Tstp!r}", name="Tstp")
        if reading not in ("gain", "printed"):
            raise EstimatorError(f"DiscretePI: reading must be 'gain' or 'printed', got {reading!r}", name="reading")
        if u_limits is not None:
            lo, hi = (float(v) for v in u_limits)
            if not lo < hi:
                raise EstimatorError(f"DiscretePI: u_limits must be (low, high) with low < high, got {u_limits!r}",
                                     name="u_limits")
            u_limits = (lo, hi)
        self.TP, self.TI, self.Tstp = vals["TP"], vals["TI"], vals["Tstp"]
        c = self.TI * self.Tstp if reading == "gain" else self.TI / self.Tstp
        self.reading = reading
        self.C = np.array([c, -c])
        self.D = np.array([self.TP, -self.TP])
        self.beta = np.array([vals["beta"], vals["beta"]])
        self.u_limits = u_limits
        self.anti_windup = bool(anti_windup)
        self.reset()

    @classmethod
    def from_paper(cls, loop: Literal["angle", "torque"], **options) -> "DiscretePI":
        """The paper's gains for ``loop`` (:data:`PAPER_GAINS`); `options` as the constructor."""
        if loop not in PAPER_GAINS:
            raise EstimatorError(f"DiscretePI.from_paper: unknown loop {loop!r}; expected one of "
                                 f"{', '.join(PAPER_GAINS)}", name="loop")
        return cls(*PAPER_GAINS[loop], **options)

    def reset(self) -> None:
        """State back to zero."""
        self.x = 0.0

    def step(self, reference: float, measurement: float) -> np.ndarray:
        """Valve voltages ``[u1, u2]`` (V) for this sample; error ``reference - measurement``."""
        e = float(reference) - float(measurement)
        u = self.C * self.x + self.D * e + self.beta
        if self.u_limits is not None:
            clipped = np.clip(u, *self.u_limits)
            # conditional integration: freeze x while a clipped output would be pushed further out
            pushing = (clipped != u) & (np.sign(self.C) * np.sign(e) * np.sign(u - clipped) > 0)
            u = clipped
            if self.anti_windup and np.any(pushing):
                return u
        self.x += e
        return u
