"""Registry of the benchmark's truth plants: ``PLANTS`` (name -> factory) and ``plant(name)``."""
from __future__ import annotations

from typing import Callable

from .plant import TruthPlant, UnknownTruthName
from .plants_cylinder import pneumatic_cylinder, switched_cylinder
from .plants_drivetrain import carriage, drivetrain
from .plants_exo import exoskeleton
from .plants_hydraulic import hydraulic
from .plants_pam import pam, pam_frictionless
from .plants_textbook import coupled_tanks, dc_motor, geared_inertias, mass_spring_damper, rlc

__all__ = ["PLANTS", "FAST", "plant"]

#: Benchmark plant name -> factory returning a fresh :class:`TruthPlant`.
PLANTS: dict[str, Callable[[], TruthPlant]] = {
    "msd": mass_spring_damper,
    "dc-motor": dc_motor,
    "rlc": rlc,
    "tanks": coupled_tanks,
    "geared-inertias": geared_inertias,
    "pam": pam,
    "pam-frictionless": pam_frictionless,
    "exoskeleton": exoskeleton,
    "pneumatic-cylinder": pneumatic_cylinder,
    "switched-cylinder": switched_cylinder,
    "drivetrain": drivetrain,
    "carriage": carriage,
    "hydraulic": hydraulic,
}

#: The plants whose truths and diagnoses take seconds (all but the PAM joints, the exoskeleton and
#: the cylinders): the detuned and resampled runs' ``--plants``, and the tests' cases.
FAST: dict[str, Callable[[], TruthPlant]] = {name: PLANTS[name] for name in (
    "msd", "rlc", "geared-inertias", "carriage", "hydraulic", "drivetrain", "dc-motor", "tanks")}


def plant(name: str) -> TruthPlant:
    """A fresh truth plant by benchmark name."""
    try:
        return PLANTS[name]()
    except KeyError:
        raise UnknownTruthName(f"no benchmark plant {name!r}; available: {', '.join(PLANTS)}") from None
