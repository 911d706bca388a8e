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
from .plants_thermal import heater_pair

__all__ = ["PLANTS", "FAST", "PLANTS_BEFORE_34", "FAST_BEFORE_34", "PLANT_LISTS", "plant"]

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
    "heater-pair": heater_pair,
}

#: The plants whose truths and diagnoses take seconds (all but the PAM joints, the exoskeleton and
#: the cylinders): the detuned and resampled runs' ``--plants``, and the tests' cases.
FAST: dict[str, Callable[[], TruthPlant]] = {name: PLANTS[name] for name in (
    "msd", "rlc", "geared-inertias", "carriage", "hydraulic", "drivetrain", "dc-motor", "tanks", "heater-pair")}

#: The plants drawn until session 33, before the heater pair joined (a plant added changes which
#: plant each case is drawn on): ``--plants before-34`` and ``fast-before-34`` replay those seeds,
#: as the tests that pin a past case do
PLANTS_BEFORE_34 = {name: f for name, f in PLANTS.items() if name != "heater-pair"}
FAST_BEFORE_34 = {name: f for name, f in FAST.items() if name != "heater-pair"}
#: the named plant lists of ``--plants``
PLANT_LISTS = {"fast": FAST, "before-34": PLANTS_BEFORE_34, "fast-before-34": FAST_BEFORE_34}


def plant(name: str) -> TruthPlant:
    """A fresh truth plant by benchmark name."""
    try:
        return PLANTS[name]()
    except KeyError:
        raise UnknownTruthName(f"no benchmark plant {name!r}; available: {', '.join(PLANTS)}") from None
