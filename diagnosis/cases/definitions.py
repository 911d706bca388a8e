"""The test set: nominal library models, concealed effects, excitations and sensors.

Each :class:`Case` names an unmodified built-in model (``plants.library``),
one concealed effect (``diagnosis.cases.truth``; ``None`` for a null case),
the excitation (seeded, piecewise constant on the sample grid, DAC-quantised),
and per recorded signal its CSV column, the column's unit and the sensor's
noise sigma and resolution (quantum), both in the column's unit.

Sensor figures (typical of the instruments named; written per signal below):
linear encoder / potentiometer 0.5 mm noise, 0.1 mm counts; tachometer 1 rpm,
0.5 rpm counts; current shunt 2 mA, 1 mA counts; 12-bit voltage ADC 10 mV,
2.5 mV counts; ultrasonic level sensors 1 mm, 0.5 mm counts; torque sensor
(TS110a class) 0.05 N m, 0.01 N m counts; motor encoder speed 1 rpm, 0.1 rpm;
PAM rig (seed 000 Sec. II-A): 10000-count encoder (0.036 deg) with 0.02 deg
noise, pressure sensors 0.5 kPa, 0.2 kPa counts.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..place import Place
from . import profiles as pr
from .truth import (CubicSpring, Effect, EffectParam, InputDelay, InputSaturation, PamValveLag,
                    ResistiveEffect, SensorGain, SensorOffset)
from ..errors import UnknownCaseError

__all__ = ["Signal", "Case", "CASES", "case"]

RPM = 60.0 / (2.0 * math.pi)      # rpm per rad/s


@dataclass(frozen=True)
class Signal:
    """A recorded signal: model name, CSV column and unit, and its sensor.

    ``column value = scale * model value`` (model value in the model's unit);
    ``sigma`` (noise std) and ``quantum`` (resolution) are in the column's unit;
    ``decimals`` is the number of decimals written.  Inputs are commands:
    quantised to ``quantum`` (the DAC), no noise.
    """

    name: str
    column: str
    unit: str
    scale: float
    quantum: float
    decimals: int
    sigma: float = 0.0

    @property
    def binding(self) -> str:
        """``NAME=COLUMN:UNIT`` as the diagnose command takes it."""
        return f"{self.name}={self.column}:{self.unit}"

    @property
    def effective_sigma(self) -> float:
        """Std of noise plus quantisation error, ``sqrt(sigma^2 + quantum^2/12)``, column unit."""
        return math.sqrt(self.sigma ** 2 + self.quantum ** 2 / 12.0)


@dataclass(frozen=True)
class Case:
    """One recording with (or without) a concealed effect.

    ``excite(t, rng)`` returns the raw commands (model units, before the DAC);
    ``min_ratio`` is the documented floor of RMS(truth - nominal) of the
    affected output over the effective noise sigma (0 for null cases).
    ``equivalent`` lists places that no recording can tell apart from the
    effect's own (a 1-junction rigidly geared to it through a TF: one degree
    of freedom, the same law fits there with scaled parameters), and
    ``equivalence`` says why.
    """

    name: str
    model: str
    description: str
    effect: Effect | None
    affected: str
    inputs: tuple[Signal, ...]
    outputs: tuple[Signal, ...]
    excite: Callable
    excitation: str
    duration: float
    rate: float
    seed: int
    min_ratio: float
    time_column: str = "t_s"
    equivalent: tuple[Place, ...] = ()
    equivalence: str = ""

    @property
    def kind(self) -> str:
        return "none" if self.effect is None else self.effect.kind

    def output(self, name: str) -> Signal:
        return next(s for s in self.outputs if s.name == name)


def _p(name, value, unit, description):
    return EffectParam(name, float(value), unit, description)


# -- excitations (model units) ---------------------------------------------------------------

def _msd_force(t, rng):
    return {"F": pr.held_levels(t, rng, low=-2.0, high=2.0, hold=(0.5, 3.0))}


def _motor_staircase(t, rng):
    return {"V": pr.staircase(t, amplitude=6.0, step_time=0.25, n_levels=12)}


def _motor_levels(t, rng):
    # magnitudes 2-14 V with alternating signs, so that both driver limits (+-10 V) are reached
    size = pr.held_levels(t, rng, low=2.0, high=14.0, hold=(0.3, 1.0))
    segment = np.cumsum(np.concatenate(([0], np.diff(size) != 0)))
    return {"V": np.where(segment % 2 == 0, size, -size)}


def _rlc_steps(t, rng):
    return {"V": pr.held_levels(t, rng, low=0.0, high=5.0, hold=(0.1, 0.6))}


def _tank_inflow(t, rng):
    return {"Q_in": pr.held_levels(t, rng, low=0.1e-3, high=0.3e-3, hold=(3.0, 8.0))}


def _exo_drive(t, rng):
    trunk = pr.held_levels(t, rng, low=-0.4, high=0.4, hold=(1.0, 2.5))   # trunk flexion phases
    return {"tau_m": pr.prbs(t, rng, low=-0.2, high=0.2, bit_time=0.15), "w_h": trunk}


def _pam_cocontraction(t, rng):
    a = pr.held_levels(t, rng, low=-4.5, high=4.5, hold=(0.2, 0.8))
    return {"u1": 5.0 + a, "u2": 5.0 - a}


# -- signals ---------------------------------------------------------------------------------

_F = Signal("F", "F_N", "N", 1.0, 0.01, 2)
_X = Signal("x", "x_mm", "mm", 1e3, 0.1, 1, sigma=0.5)
_V_MOTOR = Signal("V", "u_V", "V", 1.0, 0.01, 2)
_W_LOAD = Signal("w_L", "wL_rpm", "rpm", RPM, 0.5, 1, sigma=1.0)
_I_MOTOR = Signal("i", "i_mA", "mA", 1e3, 1.0, 0, sigma=2.0)
_V_RLC = Signal("V", "vs_V", "V", 1.0, 0.01, 2)
_VC = Signal("v_C", "vC_mV", "mV", 1e3, 2.5, 1, sigma=10.0)
_I_RLC = Signal("i", "i_mA", "mA", 1e3, 0.5, 1, sigma=2.0)
_Q_IN = Signal("Q_in", "Qin_L_min", "L/min", 6e4, 0.01, 2)
_H1 = Signal("h1", "h1_mm", "mm", 1e3, 0.5, 1, sigma=1.0)
_H2 = Signal("h2", "h2_mm", "mm", 1e3, 0.5, 1, sigma=1.0)
_TAU_M = Signal("tau_m", "tau_m_mNm", "mN m", 1e3, 1.0, 0)
_W_H = Signal("w_h", "w_h_deg_s", "deg/s", 180.0 / math.pi, 0.1, 1)
_TAU_S = Signal("tau_s", "tau_s_Nm", "N m", 1.0, 0.01, 2, sigma=0.05)
_W_M = Signal("w_m", "w_m_rpm", "rpm", RPM, 0.1, 1, sigma=1.0)
_U1 = Signal("u1", "u1_V", "V", 1.0, 0.01, 2)
_U2 = Signal("u2", "u2_V", "V", 1.0, 0.01, 2)
_PSI = Signal("psi", "psi_deg", "deg", 1.0, 0.036, 3, sigma=0.02)
_P1 = Signal("P1", "P1_kPa", "kPa", 1e-3, 0.2, 1, sigma=0.5)
_P2 = Signal("P2", "P2_kPa", "kPa", 1e-3, 0.2, 1, sigma=0.5)

_MSD = dict(model="mass-spring-damper", inputs=(_F,), outputs=(_X,), excite=_msd_force,
            excitation="force steps, random levels in [-2, 2] N held 0.5-3 s, DAC 0.01 N",
            duration=30.0, rate=100.0)
_MOTOR = dict(model="dc-motor", inputs=(_V_MOTOR,), outputs=(_W_LOAD, _I_MOTOR))
_TANKS = dict(model="coupled-tanks", inputs=(_Q_IN,), outputs=(_H1, _H2), excite=_tank_inflow,
              excitation="pump inflow steps, random levels in 6-18 L/min held 3-8 s, DAC 0.01 L/min",
              duration=40.0, rate=100.0, time_column="time_s")
_EXO = dict(model="exoskeleton", inputs=(_TAU_M, _W_H), outputs=(_TAU_S, _W_M), excite=_exo_drive,
            excitation="motor torque PRBS +-0.2 N m (0.15 s bits, 32 N m at the gear output), trunk "
                       "velocity phases in +-0.4 rad/s held 1-2.5 s; DAC 1 mN m, 0.1 deg/s",
            duration=10.0, rate=200.0)
_PAM = dict(model="pam", inputs=(_U1, _U2), outputs=(_PSI, _P1, _P2), excite=_pam_cocontraction,
            excitation="antagonistic valve voltages u1 = 5 + a, u2 = 5 - a, a random in +-4.5 V "
                       "held 0.2-0.8 s, DAC 0.01 V",
            duration=20.0, rate=200.0)

_COULOMB_LAW = "F_c*tanh(f/v_s)"
_STRIBECK_LAW = "(T_c + (T_s - T_c)*exp(-(f/w_st)**2))*tanh(f/w_eps)"

CASES: tuple[Case, ...] = (
    Case("msd_coulomb", effect=ResistiveEffect(
            "coulomb_friction", Place("junction", "v_mass"),
            (_p("F_c", 0.03, "N", "Coulomb friction force"),
             _p("v_s", 0.01, "m/s", "velocity scale of the tanh smoothing of sign(v)")),
            law=_COULOMB_LAW, domain="translation", zero=("F_c",)),
         affected="x", seed=101, min_ratio=5.0,
         description="dry friction on the mass: a constant 0.03 N against the motion", **_MSD),
    Case("msd_hardening", effect=CubicSpring(
            "nonlinear_stiffness", Place("junction", "v_mass"),
            (_p("k3", 0.4, "N/m^3", "cubic stiffness: extra spring force k3 x^3"),), domain="translation"),
         affected="x", seed=102, min_ratio=5.0,
         description="hardening spring: k x + k3 x^3 instead of k x", **_MSD),
    Case("msd_null", effect=None, affected="x", seed=103, min_ratio=0.0,
         description="null case: the nominal mass-spring-damper with sensor noise only", **_MSD),
    Case("dcmotor_stribeck", effect=ResistiveEffect(
            "stribeck_friction", Place("junction", "w_load"),
            (_p("T_c", 0.01, "N m", "Coulomb friction torque at the load"),
             _p("T_s", 0.025, "N m", "static (breakaway) friction torque"),
             _p("w_st", 2.0, "rad/s", "Stribeck velocity"),
             _p("w_eps", 0.05, "rad/s", "velocity scale of the tanh smoothing of sign(w)")),
            law=_STRIBECK_LAW, domain="rotation", zero=("T_c", "T_s")),
         affected="i", seed=201, min_ratio=5.0,
         excite=_motor_staircase,
         excitation="stepped voltage ramp +-6 V (0.5 V every 0.25 s), plateaus at many load speeds "
                    "of both signs, DAC 0.01 V",
         duration=12.0, rate=200.0,
         description="load-bearing friction that is higher at low speed (Stribeck)",
         equivalent=(Place("junction", "w_motor"),),
         equivalence="TF n rigidly gears w_load to w_motor (one degree of freedom): a friction torque T(w) "
                     "at the load equals n T(n w_m) at the motor",
         **_MOTOR),
    Case("dcmotor_saturation", effect=InputSaturation(
            "saturation", Place("input", "V"),
            (_p("limit", 10.0, "V", "the driver delivers at most +-limit"),)),
         affected="w_L", seed=202, min_ratio=5.0,
         excite=_motor_levels,
         excitation="voltage command steps, random magnitudes 2-14 V of alternating sign held "
                    "0.3-1 s, DAC 0.01 V",
         duration=12.0, rate=200.0,
         description="the motor driver saturates at +-10 V; the command reaches +-14 V", **_MOTOR),
    Case("rlc_sensor_gain", model="rlc", effect=SensorGain(
            "sensor_gain", Place("output", "v_C"),
            (_p("gain", 0.95, "1", "reading / true capacitor voltage"),)),
         affected="v_C", seed=301, min_ratio=5.0,
         inputs=(_V_RLC,), outputs=(_VC, _I_RLC), excite=_rlc_steps,
         excitation="source voltage steps, random levels in 0-5 V held 0.1-0.6 s, DAC 0.01 V",
         duration=10.0, rate=500.0,
         description="the capacitor-voltage probe reads 5 % low"),
    Case("tanks_leak", effect=ResistiveEffect(
            "leak", Place("junction", "P1"),
            (_p("G_leak", 3e-9, "m^3/(s Pa)", "laminar leak conductance of tank 1: Q = G_leak P1"),),
            law="G_leak*e", flow_law=True, domain="hydraulic", zero=("G_leak",)),
         affected="h1", seed=401, min_ratio=5.0,
         description="tank 1 leaks: an extra outflow proportional to its pressure", **_TANKS),
    Case("tanks_sensor_offset", effect=SensorOffset(
            "sensor_offset", Place("output", "h2"),
            (_p("offset", 0.01, "m", "level sensor 2 reads this much high"),)),
         affected="h2", seed=402, min_ratio=5.0,
         description="level sensor 2 is mounted 10 mm off: constant offset", **_TANKS),
    Case("exo_viscous", effect=ResistiveEffect(
            "viscous_friction", Place("junction", "w_m"),
            (_p("b_v", 0.03e-3, "N m s/rad", "extra viscous friction on the motor shaft"),),
            law="b_v*f", domain="rotation", zero=("b_v",)),
         affected="tau_s", seed=501, min_ratio=5.0,
         description="extra viscous drag on the motor side (bearing grease), 6 % of the nominal b_f",
         equivalent=(Place("junction", "w_g"),),
         equivalence="TF r_g rigidly gears w_g to w_m (one degree of freedom): a viscous b at w_m equals "
                     "r_g^2 b at w_g",
         **_EXO),
    Case("exo_delay", effect=InputDelay(
            "transport_delay", Place("input", "tau_m"),
            (_p("delay", 0.002, "s", "the drive applies the torque command this much late"),)),
         affected="tau_s", seed=502, min_ratio=5.0,
         description="a 2 ms communication delay between the torque command and the motor", **_EXO),
    Case("exo_null", effect=None, affected="tau_s", seed=503, min_ratio=0.0,
         description="null case: the nominal exoskeleton drive with sensor noise only", **_EXO),
    Case("pam_valve_lag", effect=PamValveLag(
            "valve_lag", Place("input", "u1"),
            (_p("tau", 0.12, "s", "time constant of valve 1's driver: tau du_v/dt = u1 - u_v"),)),
         affected="P1", seed=601, min_ratio=5.0,
         description="valve 1 follows its command with a 120 ms first-order lag", **_PAM),
    Case("pam_pressure_friction", effect=ResistiveEffect(
            "pressure_dependent_friction", Place("junction", "seesaw"),
            (_p("T_0", 0.01, "N m", "pressure-independent part of the extra Coulomb torque"),
             _p("k_p", 1e-7, "N m/Pa", "growth of the Coulomb torque with the summed gauge pressure"),
             _p("w_s", 0.05, "rad/s", "velocity scale of the tanh smoothing of sign(w)")),
            law="(T_0 + k_p*(P_1 + P_2 - 2*P_out))*tanh(f/w_s)", domain="rotation", zero=("T_0", "k_p")),
         affected="psi", seed=602, min_ratio=5.0,
         description="extra seal friction in the joint that grows with the muscle pressures", **_PAM),
    Case("pam_null", effect=None, affected="psi", seed=603, min_ratio=0.0,
         description="null case: the nominal PAM joint (Kikuuwe friction included) with sensor noise only",
         **_PAM),
)


def case(name: str) -> Case:
    """The case called `name` (KeyError listing the known ones)."""
    for c in CASES:
        if c.name == name:
            return c
    raise UnknownCaseError(f"no diagnosis case {name!r}; cases are {', '.join(c.name for c in CASES)}")
