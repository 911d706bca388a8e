"""The single-PAM plant of seed 002 (eq. (15) of [1]_) as state equations for the FMU,
and the difference equation itself as the reference the FMU loop is checked against.

Eq. (15) of [1]_, identified from isobaric experiments on a 30 mm Shadow muscle
(input ``u``: the inflation-pressure command, output ``y``: contraction in mm;
the paper gives no unit for ``u``), sampled at ``T = 1 ms``:

.. math::

    y_k = 0.3914\\,y_{k-1} + 0.333\\,y_{k-2} + 0.2745\\,y_{k-3}
        + 0.0111\\,u_{k-1} + 0.0102\\,u_{k-2} + 0.0093\\,u_{k-3}

i.e. :math:`G(z) = (0.0111 z^2 + 0.0102 z + 0.0093) / (z^3 - 0.3914 z^2 - 0.333 z - 0.2745)`,
DC gain 27.8 mm per unit of ``u``.

Continuous plant for the FMU
----------------------------
An FMU integrates continuous state equations, so the plant is the unique real
continuous LTI system whose **zero-order-hold discretisation at T = 1 ms is
eq. (15) exactly** (principal matrix logarithm: no pole of (15) lies on the
negative real axis, so it exists and is real).  Each discrete pole
:math:`\\lambda_i` with residue :math:`R_i` of :math:`G(z)` maps to the continuous
pole :math:`s_i = \\ln(\\lambda_i) / T` with residue
:math:`r_i = R_i s_i / (\\lambda_i - 1)` (the ZOH of :math:`r/(s - s_i)` is
:math:`(r/s_i)(e^{s_i T} - 1)/(z - e^{s_i T})`).  With the numbers of (15):

.. math::

    G(s) = \\frac{r_s}{s + p_s} + \\frac{c_1 s + c_0}{s^2 + 2\\sigma s + \\omega^2},
    \\quad p_s = 0.584\\ \\mathrm{s^{-1}},\\ r_s = 16.26,\\ \\sigma = 646,\\
    \\omega = 2283\\ \\mathrm{rad/s},\\ c_1 = 5.63,\\ c_0 = -2.77 \\cdot 10^4

realised in modal form (states in mm and mm/s):

.. math::

    \\dot x_s = -p_s x_s + r_s u, \\quad
    \\dot x_f = -2\\sigma x_f + w + c_1 u, \\quad
    \\dot w = -\\omega^2 x_f + c_0 u, \\qquad y = x_s + x_f .

Why not a bond graph: the continuous equivalent has **right-half-plane zeros**
(151.9 ± 1961.7j rad/s) and its fast mode (a lightly damped pair at 363 Hz,
zeta = 0.28, at 0.35 of the Nyquist frequency) has a *negative* static gain
(:math:`c_0 / \\omega^2 = -0.0053` mm per unit).  A passive mechanical reading
(a pneumatic R-C lag driving a Kelvin-Voigt element in series with a
mass-spring-damper, output the summed displacement) needs positive
compliances and gives a numerator without the :math:`c_1 s` term, so any bond
graph with positive parameters and a physical displacement as output changes
eq. (15).  The fast pair is most likely an artefact of the identification,
not muscle physics; we keep (15) exactly rather than a physical model that
is not the paper's.

References
----------
.. [1] Yang H., Hao L., Chen Y., Xue B., "Kalman-PID control for chattering
   phenomena of bionic elbow joint actuated by pneumatic artificial muscles",
   Control Theory & Applications (2017); seed 002 (``docs/references.md``).
"""
from __future__ import annotations

import numpy as np
import sympy as sp

from bondgraph.system import StateEquations
from .errors import ScenarioError

__all__ = ["ARX_A", "ARX_B", "T_ID", "continuous_modes", "pam_single_equations", "arx_response"]

#: eq. (15) of [1]_: coefficients of y_{k-1..k-3} and of u_{k-1..k-3}; sampling period (s).
ARX_A = (0.3914, 0.333, 0.2745)
ARX_B = (0.0111, 0.0102, 0.0093)
T_ID = 1e-3


def continuous_modes(a=ARX_A, b=ARX_B, T: float = T_ID) -> dict:
    """Modal parameters of the continuous system whose ZOH at `T` is the ARX model (a, b).

    Parameters
    ----------
    a, b : sequence of 3 float
        ``y_k = sum a_i y_{k-i} + sum b_i u_{k-i}`` (i = 1..3).
    T : float, s

    Returns
    -------
    dict
        ``p_s`` (1/s), ``r_s`` (mm/s per unit u), ``sigma`` (1/s), ``omega2`` (1/s^2),
        ``c1`` (mm/s per unit u), ``c0`` (mm/s^2 per unit u): see the module docstring.

    Raises
    ------
    ValueError
        The model does not have one real and one complex pair of poles off
        the negative real axis (the only structure this realisation handles).
    """
    den = np.array([1.0, -a[0], -a[1], -a[2]])
    num = np.array([b[0], b[1], b[2]])
    lam = np.roots(den)
    real = [x for x in lam if abs(x.imag) < 1e-12]
    cplx = [x for x in lam if x.imag > 1e-12]
    if len(real) != 1 or len(cplx) != 1 or real[0].real <= 0.0:
        raise ScenarioError(f"expected one positive real pole and one complex pair; poles are {lam}")
    dden = np.polyder(den)

    def mode(lz):
        R = np.polyval(num, lz) / np.polyval(dden, lz)      # residue of G(z) at lz (simple pole)
        s = np.log(lz) / T                                  # principal logarithm
        return s, R * s / (lz - 1.0)                        # continuous pole and residue
    s_r, r_r = mode(complex(real[0].real, 0.0))
    s_c, r_c = mode(cplx[0])
    return {"p_s": float(-s_r.real), "r_s": float(r_r.real),
            "sigma": float(-s_c.real), "omega2": float(abs(s_c) ** 2),
            "c1": float(2.0 * r_c.real), "c0": float(-2.0 * (r_c * np.conj(s_c)).real)}


def pam_single_equations(*, T: float = T_ID) -> StateEquations:
    """The single PAM of eq. (15) of [1]_ as continuous state equations (see module docstring).

    Returns
    -------
    StateEquations
        States ``x_slow_mm`` (mm), ``x_fast_mm`` (mm), ``w_fast`` (mm/s); input ``u``
        (pressure command, unit not given by the paper); output ``y_mm`` (mm);
        the six modal coefficients as parameters.  Smooth (any solver).
    """
    modes = continuous_modes(T=T)
    xs, xf, w, u = sp.symbols("x_slow_mm x_fast_mm w_fast u", real=True)
    p = {k: sp.Symbol(k, real=True) for k in modes}
    f = (-p["p_s"] * xs + p["r_s"] * u,
         -2 * p["sigma"] * xf + w + p["c1"] * u,
         -p["omega2"] * xf + p["c0"] * u)
    units = {"x_slow_mm": "mm", "x_fast_mm": "mm", "w_fast": "mm/s", "u": "", "y_mm": "mm",
             "p_s": "1/s", "r_s": "mm/s", "sigma": "1/s", "omega2": "1/s^2", "c1": "mm/s",
             "c0": "mm/s^2"}
    desc = {"x_slow_mm": "slow mode of eq. (15) (pole 0.584 1/s), mm",
            "x_fast_mm": "fast mode of eq. (15) (363 Hz pair), mm",
            "w_fast": "second state of the fast mode, mm/s",
            "u": "inflation-pressure command (process noise included)",
            "y_mm": "PAM contraction, mm (eq. (15) at the 1 ms samples)",
            "p_s": "slow pole", "r_s": "slow residue", "sigma": "fast-pair decay rate",
            "omega2": "fast-pair natural frequency squared", "c1": "fast-pair numerator, s term",
            "c0": "fast-pair numerator, constant term"}
    return StateEquations(
        name="pam_single", t=sp.Symbol("t", real=True), states=(xs, xf, w), inputs=(u,),
        params=tuple(p.values()), outputs=("y_mm",), f=f, h=(xs + xf,),
        param_values=modes, initial_state={"x_slow_mm": 0.0, "x_fast_mm": 0.0, "w_fast": 0.0},
        input_defaults={"u": 0.0}, units=units, descriptions=desc,
        owners={n: ("eq. (15) of seed 002", n) for n in (*units,)})


def arx_response(u, a=ARX_A, b=ARX_B) -> np.ndarray:
    """Output of eq. (15) from rest for the input sequence ``u`` (``y_0 = 0``).

    Parameters
    ----------
    u : array_like, shape (n,)
        ``u_k``, held over ``[kT, (k+1)T)``.

    Returns
    -------
    ndarray, shape (n,)
        ``y_k``, which depends on ``u_{k-1}, u_{k-2}, u_{k-3}`` only.
    """
    u = np.asarray(u, dtype=float)
    y = np.zeros(u.size + 3)
    up = np.concatenate([np.zeros(3), u])
    for k in range(u.size):
        i = k + 3
        y[i] = (a[0] * y[i - 1] + a[1] * y[i - 2] + a[2] * y[i - 3]
                + b[0] * up[i - 1] + b[1] * up[i - 2] + b[2] * up[i - 3])
    return y[3:]
