"""Concealed effects of the benchmark's truth plants, written apart from the catalogue.

Each effect is a small class with one magnitude ``m`` (the size the case
generator calibrates: a friction level, a leak conductance, a delay, an
offset) and shape constants drawn once per case.  They act through the doors
of :mod:`diagnosis.benchmark.plant`: an effort or flow added at a junction
(``extra``, own states for a Dahl element), a changed storage law (the
effort change of a spring or a tank, added at the junction it acts on),
the inputs before the plant (clipping, delay, lag) or the outputs after it
(offset, gain, range).  None of this imports the diagnosis catalogue.

The kinds and where they may sit (:data:`KIND_PLACES`):

============================  ================================================
junction (1: common flow)     viscous_friction, asymmetric_viscous_friction
                              (harder one way: a damper's rebound, a check
                              valve; where the flow reverses), constant_load
                              (any domain); quadratic_drag (mechanical or
                              hydraulic, not at an orifice's own flow);
                              coulomb_friction (mechanical, or an electrical
                              brush drop); stribeck_friction, hysteresis
                              (Dahl), coulomb_viscous_friction (both at once)
                              (mechanical); pressure_dependent_friction
                              (where the plant has pressures there);
                              modulated_friction (where an input sets the
                              level, through a first-order lag: an MR damper);
                              relaxation (an effort that follows the flow
                              through a lag: a cell's RC pair, a Maxwell
                              element; electrical, mechanical, hydraulic);
                              periodic_load (m sin(2 pi x/P + phi) of the
                              travel x since the start: cogging, an
                              unbalance; mechanical, not at a twist)
law (an effort in series     hysteresis (Dahl: a muscle's braid friction)
with a constitutive law)
junction (0: common effort)   leak (laminar, towards the ambient effort),
                              constant_load (a constant flow), radiation
                              (a thermal junction's c (T^4 - Ta^4))
storage (a C element)         nonlinear_stiffness (cubic hardening, the
                              nominal's linear stiffness carrying part of the
                              cubic term's average, as a linear fit would),
                              backlash (a dead band in a linear mechanical
                              spring),
                              saturation (an end stop / overflow at the
                              content's range)
inductor (an electrical I)    inductor_saturation (its differential inductance
                              L / (1 + m i^2): the flux L atan(sqrt(m) i) /
                              sqrt(m) saturates; not the catalogue's law)
input                         saturation, transport_delay, valve_lag,
                              input_offset (the plant gets the command plus
                              an offset: a biased current or force sensor),
                              input_gain (its departures from the input's
                              ambient value scaled by exp(+-m))
output                        sensor_offset, sensor_gain, saturation (range),
                              sensor_lag (a first-order lag of the sensor)
============================  ================================================
"""
from __future__ import annotations

import math

import numpy as np

from ..errors import BenchmarkError
from .plant import TruthPlant
from .simulate import NoEffect

__all__ = ["KIND_PLACES", "AT_JUNCTION", "TruthEffect", "make_effect", "places_for"]


MECHANICAL = ("translation", "rotation")
#: the doors whose effects act at a junction (a storage's or an inductor's: TruthPlant.junction_at)
AT_JUNCTION = ("junction", "storage", "inductor")

#: Where each kind makes physical sense: stiction, Dahl hysteresis and play are mechanical;
#: a sign-law drop is a Coulomb friction or an electrical brush drop; a resistance anywhere.
KIND_PLACES = {
    "coulomb_friction": ("junction1_dry",), "viscous_friction": ("junction1",),
    "stribeck_friction": ("junction1_mech",), "hysteresis": ("junction1_mech", "law1_mech"),
    "pressure_dependent_friction": ("junction1p",), "constant_load": ("junction1", "junction0"),
    "leak": ("junction0",), "nonlinear_stiffness": ("storage_linear",), "backlash": ("storage_linear1",),
    "saturation": ("input", "output", "storage_range"), "transport_delay": ("input",),
    "valve_lag": ("input",), "sensor_offset": ("output",), "sensor_gain": ("output",),
    "coulomb_viscous_friction": ("junction1_mech",), "modulated_friction": ("junction1m",),
    "asymmetric_viscous_friction": ("junction1_reversing",), "quadratic_drag": ("junction1_drag",),
    "sensor_lag": ("output",), "radiation": ("junction0_thermal",),
    "input_offset": ("input",), "relaxation": ("junction1_relax",), "input_gain": ("input",),
    "inductor_saturation": ("inductor",), "periodic_load": ("junction1_travel",),
}


def _without_laws(plant: TruthPlant):
    """`plant` seen through its junctions only (its law doors left out)."""
    from dataclasses import replace
    return replace(plant, junctions=tuple(j for j in plant.junctions if not j.law))


def places_for(plant: TruthPlant, kind: str) -> list[tuple[str, str]]:
    """The (door, name) pairs where `kind` may sit on `plant`."""
    out = []
    laws = [j for j in plant.junctions if j.law]
    plant = _without_laws(plant)
    for door in KIND_PLACES[kind]:
        if door == "law1_mech":
            out += [("junction", j.name) for j in laws if j.kind == "1" and j.domain in MECHANICAL]
        elif door == "junction1":
            out += [("junction", j.name) for j in plant.junctions if j.kind == "1"]
        elif door == "junction1_reversing":     # a direction-dependent law needs both directions
            out += [("junction", j.name) for j in plant.junctions if j.kind == "1" and not j.one_way]
        elif door == "junction1_drag":          # a body in a fluid, a fan, turbulent pipe flow
            out += [("junction", j.name) for j in plant.junctions if j.kind == "1" and not j.algebraic
                    and j.domain in MECHANICAL + ("hydraulic",)]
        elif door == "junction1_relax":         # an RC pair, a Maxwell element, a hose's compliance
            out += [("junction", j.name) for j in plant.junctions if j.kind == "1" and not j.algebraic
                    and j.domain in MECHANICAL + ("electrical", "hydraulic")]
        elif door == "junction1_mech":
            out += [("junction", j.name) for j in plant.junctions if j.kind == "1" and j.domain in MECHANICAL]
        elif door == "junction1_travel":        # a body's own travel (not a twist) a load repeats with
            out += [("junction", j.name) for j in plant.junctions if j.kind == "1" and j.domain in MECHANICAL
                    and not (j.algebraic or j.relative)]
        elif door == "junction1_dry":
            out += [("junction", j.name) for j in plant.junctions
                    if j.kind == "1" and j.domain in MECHANICAL + ("electrical",)]
        elif door == "junction1p":
            out += [("junction", j.name) for j in plant.junctions if j.kind == "1" and j.pressures]
        elif door == "junction1m":
            out += [("junction", j.name) for j in plant.junctions if j.kind == "1" and j.modulators]
        elif door == "junction0":
            out += [("junction", j.name) for j in plant.junctions if j.kind == "0"]
        elif door == "junction0_thermal":       # absolute temperatures radiate
            out += [("junction", j.name) for j in plant.junctions if j.kind == "0" and j.domain == "thermal"]
        elif door == "storage_linear":
            out += [("storage", s.name) for s in plant.storages if s.stiffness is not None]
        elif door == "storage_linear1":
            out += [("storage", s.name) for s in plant.storages if s.stiffness   # a play needs a spring
                    and plant.junction(s.junction).kind == "1"
                    and plant.junction(s.junction).domain in MECHANICAL]
        elif door == "storage_range":
            out += [("storage", s.name) for s in plant.storages if s.content_range is not None]
        elif door == "inductor":
            out += [("inductor", s.name) for s in plant.inductors]
        elif door == "input":
            out += [("input", i.name) for i in plant.inputs if i.high > i.low]
        elif door == "output":
            out += [("output", o.name) for o in plant.outputs]
    return out


class TruthEffect(NoEffect):
    """One concealed effect: `kind` at (`door`, `name`) of `plant`, magnitude `m`.

    ``scales`` holds the nominal run's typical values (``rms`` of each signal
    and input, ``range`` of each storage content and input, ``std`` of each
    output), so that shape constants are relative to the motion actually seen.
    ``shape`` holds the constants drawn once per case (fractions, signs).
    """

    def __init__(self, kind, plant, door, name, m, scales, shape):
        self.kind, self.plant, self.door, self.name = kind, plant, door, name
        self.m, self.scales, self.shape = float(m), scales, dict(shape)
        stateful = ("hysteresis", "valve_lag", "modulated_friction", "sensor_lag", "relaxation", "periodic_load")
        self.n_states = 1 if kind in stateful else 0
        self.reads_outputs = kind == "sensor_lag"
        if door == "storage":
            self.storage = plant.storage(name)
            self.junction = self.storage.junction
            # a storage's effort on a 0-junction is the junction's: a changed law is its own
            # (``extra[<storage>]``, read by the plant's right-hand side), not a flow added there
            self.law_is_effort = plant.junction(self.junction).kind == "0"
        elif door in AT_JUNCTION:
            self.junction = plant.junction_at(door, name)

    # -- where, as the diagnosis reports it ---------------------------------------------
    @property
    def place(self) -> str:
        """The place as the report's ``attached_to`` says it (storage and inductor effects act at a
        junction)."""
        if self.door in AT_JUNCTION:
            return self.plant.junction(self.junction).place
        return f"{self.door} {self.name}"

    def accepted_places(self) -> set[str]:
        """The place, its indistinguishable equivalents, and the storage element's own name."""
        out = {self.place}
        if self.door in AT_JUNCTION:
            out |= {self.plant.junction(e).place for e in self.plant.junction(self.junction).equivalent}
        if self.door in ("storage", "inductor"):
            out |= {f"storage {self.name}", f"element {self.name}"}
        return out

    def equivalent_answers(self) -> set[tuple[str, str]]:
        """``(kind, place)`` answers that no recording tells apart from this effect: a constant
        load at the junction an input's source acts on linearly (``InputSpec.load_at``, or one
        equivalent to it) is an offset of that input, and the other way round."""
        if self.kind == "constant_load" and self.door == "junction":
            here = {self.junction, *self.plant.junction(self.junction).equivalent}
            return {("input_offset", f"input {i.name}") for i in self.plant.inputs if i.load_at in here}
        if self.kind == "input_offset":
            at = next(i.load_at for i in self.plant.inputs if i.name == self.name)
            if at:
                return {("constant_load", self.plant.junction(j).place)
                        for j in (at, *self.plant.junction(at).equivalent)}
        return set()

    def describe(self) -> dict:
        return {"kind": self.kind, "place": f"{self.door} {self.name}", "magnitude": self.m,
                "shape": self.shape}

    # -- the doors ---------------------------------------------------------------------
    def z0(self, plant):
        if self.kind in ("valve_lag", "modulated_friction"):
            return np.array([self.shape["u0"]])
        if self.kind == "sensor_lag":           # the sensor rests at what the plant at rest shows
            return np.array([self.shape["y0"]])
        return np.zeros(self.n_states)

    def sensor_rates(self, y, z):
        if self.kind != "sensor_lag":
            return np.zeros(self.n_states)
        return np.array([(y[self.name] - z[0]) / self.m])   # tau dy_s/dt = y - y_s, tau = m

    def delayed_inputs(self, t, u):
        if self.door != "input" or self.kind not in ("saturation", "transport_delay", "input_offset", "input_gain"):
            return u
        u = dict(u)
        v = np.asarray(u[self.name], float)
        if self.kind == "input_offset":         # the plant gets what the record says plus m
            u[self.name] = v + self.shape["sign"] * self.m
        elif self.kind == "input_gain":         # its departures from rest scaled, gain exp(+-m) > 0
            u0 = self.shape["u0"]
            u[self.name] = u0 + math.exp(self.shape["sign"] * self.m) * (v - u0)
        elif self.kind == "saturation":
            lo, hi = self.shape["lo"], self.shape["hi"]
            # m in (0, 1]: the usable fraction of the command's span around its centre
            mid, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
            u[self.name] = np.clip(v, mid - self.m * half - self.shape["skew"] * half,
                                   mid + self.m * half - self.shape["skew"] * half)
        else:   # a delay of m seconds, whole samples plus the fraction held (ZOH stays exact on
            dt = float(t[1] - t[0])  # the sample grid only for whole samples: round to them)
            k = max(1, int(round(self.m / dt)))
            # before t = 0 the actuator delivered the ambient value the plant rested at
            u[self.name] = np.concatenate([np.full(k, self.shape.get("u0", v[0])), v[:-k]])
        return u

    def inputs_now(self, u, z):
        if self.kind == "valve_lag":
            u = dict(u)
            u[self.name] = z[0]
        return u

    def extra(self, sig, u, z):
        k, m, sh = self.kind, self.m, self.shape
        if k == "valve_lag":
            return {}, np.array([(u[self.name] - z[0]) / m])   # the actuator follows the command
        if self.door not in AT_JUNCTION:     # a sensor's lag: its rate follows the outputs
            return {}, np.zeros(self.n_states)
        j = self.junction
        if k == "inductor_saturation":        # the current's rate rises by m i^2 (L_d = L / (1 + m i^2))
            return {self.name: m * sig[j] ** 2}, np.zeros(0)
        if k == "hysteresis":
            v = sig[j]
            fc = m
            dz = sh["sigma"] * v * (1.0 - z[0] / fc * math.tanh(v / sh["eps"]))
            return {j: -z[0]}, np.array([dz])
        if self.door == "storage":
            q = sig[self.storage.name]
            s = self.storage.sign
            if k == "nonlinear_stiffness":     # hardening: e = k q + k3 q^3, k3 = m, where the
                # nominal's k holds a share alpha of the cubic's average stiffness k3 <q^4>/<q^2>,
                # at most 90 % of k itself: the truth's own linear stiffness stays positive (a
                # strong cubic on a weak spring would otherwise make it negative: bistable)
                share = min(sh["alpha"] * sh["q2"], 0.9 * self.storage.stiffness / m) if m > 0 else 0.0
                change = s * m * (q ** 3 - share * q)
                if self.law_is_effort:
                    return {self.storage.name: change}, np.zeros(0)
                return {j: -change}, np.zeros(0)
            if k == "backlash":                 # the spring carries nothing inside +-m
                kk = self.storage.stiffness
                dead = q - np.clip(q, -m, m)
                return {j: s * kk * (q - dead)}, np.zeros(0)
            if k == "saturation":               # a stiff end stop / overflow beyond the range
                lo, hi = sh["lo"], sh["hi"]
                over = max(q - hi, 0.0) - max(lo - q, 0.0)
                return {j: -s * m * over}, np.zeros(0)
        x = sig[j]
        jk = self.plant.junction(j).kind
        if k == "constant_load":
            return {j: sh["sign"] * m}, np.zeros(0)
        if k == "leak":
            return {j: -m * (x - self.plant.junction(j).ambient)}, np.zeros(0)
        if k == "radiation":                    # Stefan-Boltzmann to the room, m = eps sigma A
            return {j: -m * (x ** 4 - self.plant.junction(j).ambient ** 4)}, np.zeros(0)
        assert jk == "1"
        if k == "relaxation":                 # tau de/dt = m f - e: m settled per unit flow
            return {j: -z[0]}, np.array([(m * x - z[0]) / sh["tau"]])
        if k == "periodic_load":              # amplitude m, period P of the travel z since the start
            return {j: -m * math.sin(2.0 * math.pi * z[0] / sh["period"] + sh["phase"])}, np.array([x])
        eps = sh["eps"]
        if k == "coulomb_friction":
            return {j: -m * math.tanh(x / eps)}, np.zeros(0)
        if k == "viscous_friction":
            return {j: -m * x}, np.zeros(0)
        if k == "quadratic_drag":
            return {j: -m * x * abs(x)}, np.zeros(0)
        if k == "asymmetric_viscous_friction":   # m on the drawn side of the flow, rho m on the other
            return {j: -(m if x * sh["sign"] > 0 else sh["rho"] * m) * x}, np.zeros(0)
        if k == "coulomb_viscous_friction":   # level m, and b = beta m / v_rms: both of a size
            return {j: -m * (math.tanh(x / eps) + sh["beta"] * x / sh["v_rms"])}, np.zeros(0)
        if k == "modulated_friction":         # level m (c0 + s), s the input's lagged share of its span
            level = m * (sh["c0"] + (z[0] - sh["low"]) / sh["span"])
            return {j: -level * math.tanh(x / eps)}, np.array([(u[sh["signal"]] - z[0]) / sh["tau"]])
        if k == "stribeck_friction":
            fc = m
            fs, vs = sh["fs_over_fc"] * fc, sh["vs"]
            return {j: -(fc + (fs - fc) * math.exp(-(x / vs) ** 2)) * math.tanh(x / eps)}, np.zeros(0)
        if k == "pressure_dependent_friction":
            p = sum(sig[name] for name in self.plant.junction(j).pressures) - sh["p_ref"]
            level = m * (sh["c0"] + max(p, 0.0))
            return {j: -level * math.tanh(x / eps)}, np.zeros(0)
        raise BenchmarkError(f"effect {k} cannot act at {self.door} {self.name}")

    @property
    def changes_sensed_storage(self) -> bool:
        return self.door == "storage" and self.kind in ("nonlinear_stiffness", "backlash") and bool(self.storage.sensed)

    def read_by_sensors(self, y, ext):
        """`y` with a changed storage law in the outputs that read the storage's effort
        (``StorageSpec.sensed``): the change of its effort is ``-sign`` times the effort it adds
        at its junction (`ext`, this effect's :meth:`extra` at the same instant).  An end stop
        or overflow is an element of its own, which those sensors do not read."""
        if not self.changes_sensed_storage:
            return y
        y = dict(y)
        if self.law_is_effort:
            change = ext.get(self.storage.name, 0.0)
        else:
            change = -self.storage.sign * ext.get(self.junction, 0.0)
        for name in self.storage.sensed:
            y[name] = y[name] + change
        return y

    def sensed(self, y, z=None):
        if self.door != "output":
            return y
        y = dict(y)
        v = y[self.name]
        if self.kind == "sensor_lag":
            y[self.name] = float(z[0])
        elif self.kind == "sensor_offset":
            y[self.name] = v + self.m
        elif self.kind == "sensor_gain":
            y[self.name] = v * (1.0 + self.m)
        elif self.kind == "saturation":
            lo, hi = self.shape["lo"], self.shape["hi"]
            mid, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
            y[self.name] = min(max(v, mid - self.m * half), mid + self.m * half)
        return y


def make_effect(kind, plant, door, name, m, scales, shape) -> TruthEffect:
    """The effect object for `kind` at (`door`, `name`) with magnitude `m`."""
    return TruthEffect(kind, plant, door, name, m, scales, shape)
