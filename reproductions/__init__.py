"""reproductions: the papers' closed-loop scenarios, the seed plants exported as FMUs in the co-simulation master.

An application of the engine (:mod:`cosim`), above it in the layer order; used by
:mod:`sweeps` and the ``bondcosim`` command.

Each scenario is a module with ``NAME``, ``DESCRIPTION`` and
``run(plot_dir=None, *, quick=False) -> dict``: it exports its plant as an
FMU, co-simulates it with its estimators and controllers, saves its plots in
``plot_dir`` (if given) and returns its numbers, JSON-ready.  ``quick`` runs a
shortened version for tests.  ``bondcosim cosim NAME [--json] [--plot DIR]``
runs one.

A scenario that can be varied (sweeps, Monte-Carlo) also has ``PARAMETERS``
(name -> :class:`bondgraph.params.Param`: default value, unit, description)
and ``export_fmus(directory)``, and its ``run`` takes ``params`` (values
replacing the defaults), ``seed`` (its noise) and ``fmu_dir`` (FMUs exported
once by ``export_fmus`` and reused, each run setting its parameters as FMU
parameters before initialisation).  :func:`parameters`, :func:`export_fmus`
and :func:`run` below are the registry's entry to them.

=====================  =========================================================
``pam-pi``             the PAM joint under a plain PI angle loop
``pam-ukf``            UKF estimating angle and torque from the two pressures (seed 000)
``pam-sensorless-pi``  UKF-based encoder-less angle PI and torque PI (seed 000)
``kpid``               single-PAM plant, PID vs Kalman-filter PID (seed 002)
``exo-lqi``            exoskeleton: Kalman observer + LQI with double integral action (seed 004)
=====================  =========================================================
"""
from __future__ import annotations

import importlib

from .errors import ParameterError, UnknownNameError

__all__ = ["names", "describe", "run", "parameters", "export_fmus", "headline_metrics", "SCENARIOS"]

#: Scenario name -> module (in this package).
SCENARIOS = {
    "pam-pi": "pam_pi",
    "pam-ukf": "pam_ukf",
    "kpid": "kpid",
    "pam-sensorless-pi": "pam_sensorless_pi",
    "exo-lqi": "exo_lqi",
}


def _module(name: str):
    if name not in SCENARIOS:
        raise UnknownNameError("scenario", name, SCENARIOS)
    return importlib.import_module(f"{__name__}.{SCENARIOS[name]}")


def names() -> list[str]:
    """Names of the scenarios."""
    return list(SCENARIOS)


def describe(name: str) -> str:
    """One line on scenario `name`."""
    return _module(name).DESCRIPTION


def parameters(name: str) -> dict:
    """The parameters a run of scenario `name` may vary: name -> ``Param`` (default value, SI unit,
    description); empty if the scenario takes none.

    Raises
    ------
    UnknownNameError
        No scenario has that name.
    """
    return dict(getattr(_module(name), "PARAMETERS", {}))


def headline_metrics(name: str) -> tuple:
    """The scenario's main numbers, as flattened result keys (``"ukf.angle.I"``), for sweep plots;
    empty if it names none (``SWEEP_METRICS`` of its module)."""
    return tuple(getattr(_module(name), "SWEEP_METRICS", ()))


def export_fmus(name: str, directory) -> dict:
    """Export scenario `name`'s FMUs into `directory` for ``run(..., fmu_dir=directory)``.

    Returns
    -------
    dict str -> pathlib.Path
        The FMUs by role; empty if the scenario builds none ahead.
    """
    module = _module(name)
    return dict(module.export_fmus(directory)) if hasattr(module, "export_fmus") else {}


def run(name: str, plot_dir=None, *, quick: bool = False, params=None, seed=None, fmu_dir=None) -> dict:
    """Run scenario `name`; returns its numbers (see the module docstring).

    Parameters
    ----------
    name : str
    plot_dir : path-like, optional
    quick : bool
    params : mapping str -> float, optional
        Values (SI) of :func:`parameters` replacing their defaults.
    seed : int, optional
        Seed of the scenario's noise (default: the scenario's own).
    fmu_dir : path-like, optional
        FMUs of :func:`export_fmus`, reused instead of exported for this run.

    Raises
    ------
    UnknownNameError
        No scenario has that name, or a parameter it does not have (the message lists them).
    ParameterError
        `params`, `seed` or `fmu_dir` given to a scenario that cannot take them.
    """
    module = _module(name)
    extra = {}
    if params:
        known = getattr(module, "PARAMETERS", None)
        if not known:
            raise ParameterError(f"scenario {name!r} takes no parameters (scenarios that do: "
                                 f"{', '.join(n for n in SCENARIOS if parameters(n)) or 'none'})",
                                 name=next(iter(params)))
        unknown = sorted(set(params) - set(known))
        if unknown:
            raise UnknownNameError("parameter", unknown[0], known, f"scenario {name}")
        extra["params"] = dict(params)
    if seed is not None:
        extra["seed"] = int(seed)
    if fmu_dir is not None:
        extra["fmu_dir"] = fmu_dir
    if extra and not hasattr(module, "PARAMETERS"):
        raise ParameterError(f"scenario {name!r} takes no seed, parameters or FMU directory",
                             name=next(iter(extra)))
    return module.run(plot_dir, quick=quick, **extra)
