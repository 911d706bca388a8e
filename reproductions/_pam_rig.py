"""The "rig": the PAM joint of seed 000 with parameters perturbed as a real rig differs from its model.

The UKF scenarios of seed 000 ([1]_, Secs. III-IV) estimate the joint from a
model identified on a real rig, and the rig never matches the model exactly.
To make synthetic recordings that test what the paper tests, the plant in the
co-simulation is the same ``pam`` bond graph ([2]_) with the parameters the
identification of [1]_ is least sure of scaled by the factors of
:data:`RIG_PERTURBATION`; the estimators keep the nominal Table II values.

==========  =======  ===========================================================
parameter   factor   reason
==========  =======  ===========================================================
``A1``      1.10     filling orifice area: the valve's effective area is a fitted
                     lumped value (Table II), spread between valve units and
                     with supply-line losses; 10 % is a typical spread.
``A2``      0.92     exhaust orifice area: silencer and fitting losses make the
                     effective exhaust area smaller than the fitted one.
``k1``      1.05     polytropic index of the flow term, eq. (4): heat exchange
                     with the muscle wall depends on the rate of filling; the
                     paper fits a single constant (between isothermal 1.0 and
                     adiabatic 1.4).
``k2``      1.15     polytropic index of the volume term, eq. (4): fitted from
                     few motions, the least determined of the two.
``c_s``     1.20     viscous friction: bearing lubrication and temperature.
``mu_s``    0.85     shaft Coulomb coefficient: wear and bearing preload.
``mu_p``    1.20     tube Coulomb coefficient (Table II "T'_p"): tube routing,
                     re-assembled between experiments.
==========  =======  ===========================================================

The factors lie between a few % and 20 %, as the issue asks; all others
(geometry, masses, gas constants, force polynomials) are the nominal values.

References
----------
.. [1] T. Shin, T. Ibayashi, K. Kogiso, "Detailed dynamic model of antagonistic
   PAM system and its experimental validation: sensor-less angle and torque
   control with UKF", seed 000 (``docs/references.md``).
.. [2] ``docs/pam-conventions.md``; :func:`plants.library.pam.pam`.
"""
from __future__ import annotations

from functools import lru_cache
from pathlib import Path
from types import MappingProxyType
from typing import Mapping

import numpy as np

from plants.blockdiagram import pam as pam_bd
from plants.library.pam import FRICTION_STEP, pam, parameter_values
from fmus import export
from .errors import ScenarioError

__all__ = ["RIG_PERTURBATION", "rig_params", "rig_graph", "nominal_equations", "export_rig",
           "rig_start_values", "add_pressure_noise"]

#: Parameter name -> factor (1) applied to its Table II value on the rig (see the module docstring).
RIG_PERTURBATION: Mapping[str, float] = MappingProxyType({
    "A1": 1.10, "A2": 0.92, "k1": 1.05, "k2": 1.15, "c_s": 1.20, "mu_s": 0.85, "mu_p": 1.20,
})


def rig_params(overrides: Mapping[str, float] | None = None) -> dict[str, float]:
    """All ``pam`` parameters of the rig (SI): Table II times :data:`RIG_PERTURBATION`.

    Parameters
    ----------
    overrides : mapping str -> float, optional
        Absolute values (SI) replacing those of the rig, e.g. a Monte-Carlo
        draw ``{"A1": 6.1e-8}`` (m^2).

    Returns
    -------
    dict str -> float
        Every name of :data:`plants.library.pam.PARAMETERS`, SI units.

    Raises
    ------
    ParameterError
        An override names no ``pam`` parameter (the message lists them) or is not finite.

    Examples
    --------
    >>> p = rig_params()
    >>> round(p["A1"] / 5.184e-8, 6), p["J"]
    (1.1, 0.0004263)
    """
    nominal = parameter_values()
    rig = {name: nominal[name] * factor for name, factor in RIG_PERTURBATION.items()}
    return parameter_values({**rig, **dict(overrides or {})})


def rig_graph(*, locked: bool = False):
    """The rig as a bond graph: ``pam`` (or ``pam-locked``) with :func:`rig_params`.

    Parameters
    ----------
    locked : bool
        ``True``: the joint held at psi = 0 (the paper's torque tests).

    Returns
    -------
    BondGraph
    """
    return pam("locked" if locked else "full", params=rig_params())


@lru_cache(maxsize=2)
def nominal_equations(*, locked: bool = False):
    """State equations of the nominal ``pam`` (or ``pam-locked``), derived once per process.

    Deriving them takes seconds; the rig FMU and the estimators share them
    (the rig differs in parameter values only).

    Returns
    -------
    StateEquations
        Parameters at their Table II values.
    """
    return pam("locked" if locked else "full").equations()


def export_rig(path, *, locked: bool = False) -> Path:
    """Export the rig as an FMI 2.0 FMU (Co-Simulation and Model Exchange).

    Parameters
    ----------
    path : str or path-like
        The ``.fmu`` file to write.
    locked : bool
        ``True``: the ``pam-locked`` variant (psi = 0), for torque control.

    Returns
    -------
    pathlib.Path
        The FMU written (internal RK4 sub-step 0.25 ms, as the conventions fix
        for ``pam``); its parameter start values are :func:`rig_params`, its
        inputs ``u1``, ``u2`` (V), outputs ``psi`` (deg), ``P1``, ``P2`` (Pa abs),
        ``tau`` (N m), states ``q_psi`` (rad), ``p_J`` (N m s; not when
        locked), ``P_1``, ``P_2`` (Pa abs).
    """
    identifier = "pam_rig_locked" if locked else "pam_rig"
    eqs = nominal_equations(locked=locked)
    values = rig_params()
    # the nominal equations with the rig's parameter values as the FMU's start values; the
    # conventions' scheme for both variants: 4 RK4 sub-steps per 1 ms sample
    return export(eqs, path, params={name: values[name] for name in eqs.param_names},
                  identifier=identifier, solver_step=FRICTION_STEP,
                  description=f"antagonistic PAM joint of seed 000, rig parameters "
                              f"({', '.join(f'{k} x{v:g}' for k, v in RIG_PERTURBATION.items())})"
                              f"{', locked at psi = 0' if locked else ''}")


def rig_start_values(u0=(5.0, 5.0), *, locked: bool = False, params=None) -> dict[str, float]:
    """FMU start values: the rig at rest under constant valve commands `u0`.

    The pressures are the rig's static pressures at `u0` and the angle the
    rig's friction-free rest angle (:func:`plants.blockdiagram.pam.equilibrium`
    with :func:`rig_params`): physical, but not what an estimator built on the
    nominal model would assume.

    Parameters
    ----------
    u0 : sequence of 2 floats, V
        Valve commands ``(u1, u2)`` held before t = 0, within [0, 10].
    locked : bool
        ``True``: for :func:`export_rig` with ``locked=True`` (no ``q_psi``, ``p_J``).
    params : mapping str -> float, optional
        The rig's parameter values (SI; default :func:`rig_params`).

    Returns
    -------
    dict str -> float
        ``u1``, ``u2`` (V), ``P_1``, ``P_2`` (Pa abs), and unless locked
        ``q_psi`` (rad) and ``p_J`` (N m s, zero: at rest).

    Raises
    ------
    ValueError
        `u0` is not two finite voltages within [0, 10] V.
    """
    u = np.asarray(u0, dtype=float)
    if u.shape != (2,) or not np.all(np.isfinite(u)) or np.any((u < 0.0) | (u > 10.0)):
        raise ScenarioError(f"rig_start_values: u0 must be two voltages within [0, 10] V, got {u0!r}")
    values = rig_params() if params is None else dict(params)
    psi, _, P1, P2 = pam_bd.equilibrium(u, values, variant="locked" if locked else "full")
    start = {"u1": float(u[0]), "u2": float(u[1]), "P_1": float(P1), "P_2": float(P2)}
    if not locked:
        start.update(q_psi=float(psi), p_J=0.0)
    return start


def add_pressure_noise(p, rng: np.random.Generator, sigma_pa: float) -> np.ndarray:
    """Pressure readings: `p` plus white Gaussian noise of standard deviation `sigma_pa`.

    Parameters
    ----------
    p : array_like, Pa
        True pressures (any shape).
    rng : numpy.random.Generator
        Seeded by the caller, for reproducible recordings.
    sigma_pa : float, Pa
        Noise standard deviation, >= 0.

    Returns
    -------
    ndarray, Pa
        Same shape as `p`.

    Raises
    ------
    ValueError
        `sigma_pa` negative or not finite.
    """
    if not np.isfinite(sigma_pa) or sigma_pa < 0.0:
        raise ScenarioError(f"add_pressure_noise: sigma_pa must be a finite value >= 0 Pa, got {sigma_pa!r}")
    p = np.asarray(p, dtype=float)
    return p + rng.normal(0.0, sigma_pa, size=p.shape)
