"""Closed-loop scenarios: the seed plants exported as FMUs, in the co-simulation master.

Each scenario is a module with ``NAME``, ``DESCRIPTION`` and
``run(plot_dir=None, *, quick=False) -> dict``: it exports its plant as an
FMU, co-simulates it with its estimators and controllers, saves its plots in
``plot_dir`` (if given) and returns its numbers, JSON-ready.  ``quick`` runs a
shortened version for tests.  ``bondcosim cosim NAME [--json] [--plot DIR]``
runs one.

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

from cosim.errors import UnknownNameError

__all__ = ["names", "describe", "run", "SCENARIOS"]

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


def run(name: str, plot_dir=None, *, quick: bool = False) -> dict:
    """Run scenario `name`; returns its numbers (see the module docstring).

    Raises
    ------
    UnknownNameError
        No scenario has that name (the message lists them).
    """
    return _module(name).run(plot_dir, quick=quick)
