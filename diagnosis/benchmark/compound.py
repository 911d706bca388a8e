"""Compound cases: two concealed effects in one recording (``--compound``).

A real rig rarely misses one thing: a ball-screw axis modelled as a rigid mass lacks viscous and
Coulomb friction and a force offset at once.  A compound case adds to the drawn effect a second
one of another kind, drawn from a stream of its own (:func:`second_effect`), each sized alone as
:func:`~diagnosis.benchmark.draw.realise` sizes one, then simulated together
(:class:`CompoundEffect`).  The sensors' noise is the first effect's case's.

A second effect is one a rig could have besides the first: another kind, and not at the same
input, output or storage element; not a second friction law at the same 1-junction or at one no
recording tells apart from it (a rigidly geared one): two frictions at one contact are one law,
``coulomb_viscous_friction`` among them; not at a second algebraic junction (the truth solves one
junction's flow with its effects) nor on the junction of a storage law its sensors read.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..errors import BenchmarkError
from .draw import KINDS, CaseSpec, Realised, realise
from .effects import AT_JUNCTION, places_for
from .simulate import NoEffect, simulate_truth

__all__ = ["CompoundEffect", "second_effect", "realise_compound", "compound_label", "visibility", "FRICTIONS"]

#: the kinds that are a friction law of a 1-junction: two of them at one junction are one law
FRICTIONS = ("coulomb_friction", "viscous_friction", "stribeck_friction", "coulomb_viscous_friction",
             "pressure_dependent_friction", "modulated_friction", "hysteresis")


class CompoundEffect(NoEffect):
    """Several effects at once: their input changes in turn, their junction efforts summed, their
    own states side by side, their sensor changes in turn.  Reports as the first effect (``kind``,
    ``place``); ``door``/``junction`` name the algebraic junction one of them acts at, if any, so
    that :func:`~diagnosis.benchmark.simulate.effect_extra` solves its flow with all of them."""

    def __init__(self, effects, plant):
        self.effects = list(effects)
        first = self.effects[0]
        self.kind, self.plant = first.kind, plant
        algebraic = [e for e in self.effects if getattr(e, "door", None) == "junction"
                     and plant.junction(e.junction).algebraic]
        lead = algebraic[0] if algebraic else first
        self.door, self.name = lead.door, lead.name
        if hasattr(lead, "junction"):
            self.junction = lead.junction
        self.n_states = sum(e.n_states for e in self.effects)
        self._cuts = np.cumsum([0] + [e.n_states for e in self.effects])

    @property
    def place(self):
        return self.effects[0].place

    def accepted_places(self):
        return self.effects[0].accepted_places()

    def equivalent_answers(self):
        return self.effects[0].equivalent_answers()

    def describe(self) -> dict:
        return {**self.effects[0].describe(), "also": [e.describe() for e in self.effects[1:]]}

    def _own(self, z, i):
        return z[self._cuts[i]:self._cuts[i + 1]]

    def z0(self, plant):
        return np.concatenate([e.z0(plant) for e in self.effects])

    def delayed_inputs(self, t, u):
        for e in self.effects:
            u = e.delayed_inputs(t, u)
        return u

    def inputs_now(self, u, z):
        for i, e in enumerate(self.effects):
            u = e.inputs_now(u, self._own(z, i))
        return u

    def extra(self, sig, u, z):
        total, rates = {}, []
        for i, e in enumerate(self.effects):
            ext, dz = e.extra(sig, u, self._own(z, i))
            for k, v in ext.items():
                total[k] = total.get(k, 0.0) + v
            rates.append(np.asarray(dz, float))
        return total, (np.concatenate(rates) if rates else np.zeros(0))

    @property
    def changes_sensed_storage(self) -> bool:
        return any(e.changes_sensed_storage for e in self.effects)

    def read_by_sensors(self, y, ext):
        # a storage effect reads its own junction's entry of `ext`, which no other effect shares
        # (second_effect keeps other effects off that junction)
        for e in self.effects:
            y = e.read_by_sensors(y, ext)
        return y

    @property
    def reads_outputs(self) -> bool:
        return any(e.reads_outputs for e in self.effects)

    def sensor_rates(self, y, z):
        return np.concatenate([e.sensor_rates(y, self._own(z, i)) for i, e in enumerate(self.effects)])

    def sensed(self, y, z=None):
        for i, e in enumerate(self.effects):
            y = e.sensed(y, None if z is None else self._own(z, i))
        return y


def _junction_of(plant, door, name):
    return plant.junction_at(door, name) if door in AT_JUNCTION else None


def _compatible(plant, first: CaseSpec, kind, door, name) -> bool:
    """Whether (`kind`, `door`, `name`) may join the effect of `first` on `plant` (module doc)."""
    if kind == first.kind:
        return False
    if (door, name) == (first.door, first.name) and door in ("input", "output", "storage", "inductor"):
        return False
    j1, j2 = _junction_of(plant, first.door, first.name), _junction_of(plant, door, name)
    if j1 is not None and j2 is not None and (j1 == j2 or j2 in plant.junction(j1).equivalent):
        if kind in FRICTIONS and first.kind in FRICTIONS:
            return False
        sensed = [d for d, n in ((first.door, first.name), (door, name))
                  if d == "storage" and plant.storage(n).sensed]
        if sensed:
            return False
    algebraic = {j for j in (j1, j2) if j is not None and plant.junction(j).algebraic}
    return len(algebraic) <= 1


def second_effect(first: CaseSpec, plant, kinds=KINDS) -> CaseSpec | None:
    """The second effect of the compound case `first` on `plant` (a built truth plant), or None for
    a null case or where none of `kinds` fits: kind, place, size and effect-to-noise drawn from the
    stream ``[first.seed, 13]``; its seed and excitation are the first's (the same commands)."""
    if first.kind == "none":
        return None
    rng = np.random.default_rng([first.seed, 13])
    options = [(k, d, n) for k in kinds for d, n in places_for(plant, k) if _compatible(plant, first, k, d, n)]
    if not options:
        return None
    kinds = sorted({k for k, _, _ in options})
    kind = str(rng.choice(kinds))
    places = [(d, n) for k, d, n in options if k == kind]
    door, name = places[int(rng.integers(len(places)))]
    return CaseSpec(first.index, first.seed, first.plant, kind, door, name,
                    target_change=float(np.exp(rng.uniform(np.log(0.03), np.log(0.3)))),
                    ratio=first.ratio, excitation=first.excitation)


def realise_compound(first: CaseSpec, second: CaseSpec, plant) -> Realised:
    """The case `first` with the effect of `second` too: each sized alone on the same commands,
    then simulated together; the first's noise.  ``rec.also`` is the second's realisation."""
    rec = realise(first, plant)
    also = realise(replace(second, seed=first.seed, excitation=first.excitation), plant)
    effect = CompoundEffect([rec.effect, also.effect], plant)
    truth = simulate_truth(plant, rec.t, rec.u, effect, signals=plant.drifts)
    if not truth["_finite"]:
        raise BenchmarkError(f"{compound_label(first, second)}: the truth with both effects is not finite")
    rec.visible = (visibility(truth, also.truth, rec.sigma), visibility(truth, rec.truth, rec.sigma))
    rec.effect, rec.truth, rec.also = effect, truth, also
    rec.calibration_runs += also.calibration_runs + 1
    return rec


def visibility(both: dict, without: dict, sigma: dict) -> float:
    """An effect's effect-to-noise in a compound truth: the largest over the outputs of the rms of
    `both` (the truth with both effects) less `without` (with the other effect alone), over the
    noise's standard deviation.  Each effect is sized alone; together, one may hide the other (a
    friction that slows a shaft below the range its speed sensor clips at).  Below the draw's
    least ratio (:data:`~diagnosis.benchmark.draw.RATIOS`), the benchmark does not ask for it."""
    ratios = [float(np.sqrt(np.mean((both[o] - without[o]) ** 2))) / s for o, s in sigma.items() if s > 0]
    return max(ratios, default=0.0)


def compound_label(first: CaseSpec, second: CaseSpec | None) -> str:
    """The case's label with its second effect: ``LABEL+KIND@DOOR:NAME``."""
    return first.label if second is None else f"{first.label}+{second.kind}@{second.door}:{second.name}"
