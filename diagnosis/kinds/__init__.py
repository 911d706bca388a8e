"""The kinds of missing physics, one module per kind, in a registry.

Each module defines one :class:`~diagnosis.kinds.base.Kind` subclass and registers it
(:func:`~diagnosis.kinds.base.register`); importing this package imports them all, in the catalogue
order (:data:`KINDS`: issue 6's kinds, then ``constant_load``, then issue 11's friction laws).
Adding a kind is one new module here and its line below (``docs/diagnosis.md``, "Adding a kind").

Helpers shared by a family live beside them: :mod:`~diagnosis.kinds.friction_common` (the
smoothed sign, the friction levels), :mod:`~diagnosis.kinds.storage_common` (a C's scales and
units), :mod:`~diagnosis.kinds.signal_common` (an input's record and resting value).
"""
from __future__ import annotations

from . import (coulomb_friction, viscous_friction, stribeck_friction, pressure_dependent_friction,
               leak, heat_transfer, valve_lag, transport_delay, hysteresis, backlash, nonlinear_stiffness,
               saturation, sensor_offset, sensor_gain, constant_load, coulomb_viscous_friction,
               modulated_friction, asymmetric_viscous_friction, quadratic_drag, sensor_lag, radiation, input_offset,
               input_gain, relaxation, inductor_saturation, periodic_load, nominal_value)
from .base import DOORS, REGISTRY, Kind, Proposal, Site, extends, kind_named, register

__all__ = ["KINDS", "MODULES", "REGISTRY", "DOORS", "Kind", "Proposal", "Site", "extends", "kind_named",
           "register"]

#: The kind modules, in the catalogue order (a new kind: its module here and in the import above).
MODULES = (coulomb_friction, viscous_friction, stribeck_friction, pressure_dependent_friction, leak, heat_transfer,
           valve_lag, transport_delay, hysteresis, backlash, nonlinear_stiffness, saturation, sensor_offset,
           sensor_gain, constant_load, coulomb_viscous_friction, modulated_friction, asymmetric_viscous_friction,
           quadratic_drag, sensor_lag, radiation, input_offset, input_gain,
           relaxation, inductor_saturation, periodic_load, nominal_value)

#: The vocabulary, in the catalogue order (the registration order).
KINDS = tuple(REGISTRY)
