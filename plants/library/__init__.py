"""Ready-made bond graphs, by name.

``names()`` lists them, ``build(name)`` returns a fresh graph, ``describe(name)``
gives one line.  Textbook graphs: ``mass-spring-damper``, ``dc-motor``,
``rlc``, ``coupled-tanks``, ``geared-inertias`` (derivative causality),
``resistor-loop`` and ``resistor-loop-nl`` (algebraic loops, linear and
nonlinear), ``chain`` (the derivation benchmark, 5 stages).  Seed plants:
``exoskeleton`` (seed 004, Fig. 6), ``pam``, ``pam-frictionless``,
``pam-locked`` (seed 000).  Machines: ``pneumatic-cylinder``,
``drivetrain``, ``carriage``, ``hydraulic``, ``heater-pair`` (thermal).
"""
from __future__ import annotations

from typing import Callable

from .carriage import carriage
from .chain import mass_spring_chain
from .cylinder import pneumatic_cylinder
from .drivetrain import drivetrain
from .exoskeleton import exoskeleton
from .hydraulic import hydraulic
from .pam import pam
from .thermal import heater_pair
from .textbook import coupled_tanks, dc_motor, geared_inertias, mass_spring_damper, resistor_loop, rlc_series

__all__ = ["build", "names", "describe", "register", "exoskeleton", "pam", "mass_spring_chain", "mass_spring_damper", "dc_motor",
           "rlc_series", "coupled_tanks", "geared_inertias", "resistor_loop", "drivetrain", "carriage",
           "hydraulic", "pneumatic_cylinder", "heater_pair"]

_MODELS: dict[str, tuple[Callable, str]] = {}


def register(name: str, builder: Callable, description: str) -> None:
    """Make `builder` (no-argument callable returning a BondGraph) available as `name`."""
    _MODELS[name] = (builder, description)


register("mass-spring-damper", mass_spring_damper, "force on a mass with spring and damper (2 states)")
register("dc-motor", dc_motor, "DC motor, GY torque constant and TF gearbox to a damped load (2 states)")
register("rlc", rlc_series, "series RLC circuit driven by a voltage source (2 states)")
register("coupled-tanks", coupled_tanks, "two tanks with nonlinear Torricelli orifices (2 states)")
register("geared-inertias", geared_inertias, "two rigidly geared inertias: derivative causality (1 state)")
register("resistor-loop", resistor_loop, "resistive divider feeding an RC branch: linear algebraic loop")
register("resistor-loop-nl", lambda: resistor_loop(nonlinear=True),
         "the same with a cubic resistor: loop solved numerically")
register("exoskeleton", exoskeleton, "back-support exoskeleton drive, Fig. 6 of seed 004 (7 states)")
register("pam", pam, "antagonistic PAM joint, seed 000 (4 states, held Kikuuwe friction, 1 ms / 4 RK4 sub-steps)")
register("pam-frictionless", lambda: pam("frictionless"), "the PAM joint with T_f = 0 (smooth)")
register("pam-locked", lambda: pam("locked"), "the PAM joint held at psi = 0, for torque tests (2 states)")
register("chain", mass_spring_chain, "5-stage mass-spring-damper chain (the derivation benchmark)")
register("pneumatic-cylinder", pneumatic_cylinder, "seal-friction rig: ideal cylinder F = p A, imposed rod position (1 state)")
register("drivetrain", drivetrain, "two-mass drivetrain: motor, 10:1 gear, compliant shaft, load (3 states)")
register("carriage", carriage, "force-driven rigid carriage, no friction or spring: integrates its input (2 states)")
register("hydraulic", hydraulic, "pump, oil volume, pipe (inertance, laminar loss), volume, orifice to tank (3 states)")
register("heater-pair", heater_pair, "two heaters on two blocks sharing heat, convection to the room (2 states, K)")


def names() -> list[str]:
    """Names of the built-in models."""
    return list(_MODELS)


def describe(name: str) -> str:
    """One line describing model `name`."""
    return _lookup(name)[1]


def build(name: str):
    """A fresh copy of built-in model `name`."""
    return _lookup(name)[0]()


def _lookup(name: str):
    try:
        return _MODELS[name]
    except KeyError:
        from ..errors import UnknownModelError
        raise UnknownModelError(name, _MODELS, f"no built-in model named {name!r}; available: {', '.join(_MODELS)}") from None
