"""Run benchmark cases: write each recording, diagnose it as a user would, score the answer."""
from __future__ import annotations

import json
import time
import traceback
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from .compound import compound_label, realise_compound
from .draw import CaseSpec, Realised, realise

__all__ = ["Score", "glitches", "write_csv", "bindings", "score_case", "run_case", "GLITCHY", "GLITCH_SIZE"]


@dataclass
class Score:
    """The outcome of one case (JSON-ready)."""

    label: str
    plant: str
    model: str
    kind: str
    place: str
    answer_kind: str = ""
    answer_place: str = ""
    kind_ok: bool = False
    place_ok: bool = False
    # the kinds the recording cannot tell apart from the answer's first (diagnosis.alternatives), and
    # whether the concealed kind is the answer's or one of them: a measure apart from kind_ok
    indistinguishable: list = field(default_factory=list)
    kind_or_indistinguishable_ok: bool = False
    affected: str = ""
    nominal_nrmse: float = float("nan")
    improved_nrmse: float = float("nan")
    improvement: float = float("nan")     # 1 - improved / nominal, held-out, affected output
    change: float = 0.0                   # rms(truth - nominal) / std(y), affected output
    ratio: float = 0.0                    # effect-to-noise aimed at
    nominal_drifts: bool = False
    drifting_plant: bool = False
    judge: str = ""                       # how the held-out errors were measured (fit.judge)
    glitches: int = 0                     # sensor glitches written into the recording (glitches())
    # a compound case (compound.py): its second effect, and whether some answered effect names each
    # effect's kind (or lists it as not told apart) at one of its places
    also_kind: str = ""
    also_place: str = ""
    first_found: bool | None = None
    also_found: bool | None = None
    # each effect's effect-to-noise in the truth with both (compound.visibility): first, second
    first_visible: float = float("nan")
    also_visible: float = float("nan")
    answers: list = field(default_factory=list)
    parameters: dict = field(default_factory=dict)        # every answered effect's fitted values
    # a detuned nominal (--detune, detune.py): what was detuned, and whether a nominal_value answer
    # refitted that parameter (None without detuning)
    detuned: dict = field(default_factory=dict)
    detuned_named: bool | None = None
    seconds_generate: float = 0.0
    seconds_diagnose: float = 0.0
    error: str = ""


#: the share of cases whose recording has a sensor's glitches, and their size in noise standard deviations
GLITCHY, GLITCH_SIZE = 0.25, (15.0, 60.0)


def glitches(rec: Realised) -> dict:
    """The sensor glitches written into the recording of case `rec` (since session 24):
    ``{output: (samples, jumps)}``.  In :data:`GLITCHY` of the cases, 1-3 single samples of one
    varying output jump by :data:`GLITCH_SIZE` noise standard deviations (its resolution where it
    has no noise), either sign: an encoder miscount, an ADC spike.  From a random stream of their
    own, so the rest of the case and its noise are what they were."""
    rng = np.random.default_rng([rec.spec.seed, 11])
    varying = [o.name for o in rec.plant.outputs if np.ptp(rec.truth[o.name]) > 0]
    if rng.uniform() >= GLITCHY or not varying or rec.t.size < 3:
        return {}
    o = str(rng.choice(varying))
    samples = np.unique(rng.integers(1, rec.t.size - 1, int(rng.integers(1, 4))))
    sigma = rec.sigma[o] or rec.quantum[o] or 0.01 * float(np.std(rec.truth[o]))
    jumps = rng.uniform(*GLITCH_SIZE, samples.size) * rng.choice([-1.0, 1.0], samples.size) * sigma
    return {o: (samples, jumps)}


def write_csv(rec: Realised, path: Path, rng) -> list[str]:
    """The recording as a user would have it: commands as sent, outputs with noise, resolution and,
    in some cases, a sensor's glitches (:func:`glitches`).  Returns the outputs whose written
    column is constant (a user would not bind them)."""
    cols = {"t": [f"{v:.6f}" for v in rec.t]}
    for spec in rec.plant.inputs:
        cols[spec.name] = [f"{v:.10g}" for v in rec.u[spec.name]]
    glitched = glitches(rec)
    for o in rec.plant.outputs:
        y = rec.truth[o.name] + rng.normal(0.0, rec.sigma[o.name], rec.t.size)
        if o.name in glitched:
            samples, jumps = glitched[o.name]
            y[samples] += jumps
        q = rec.quantum[o.name]
        if q > 0:
            y = np.round(y / q) * q
        cols[o.name] = [f"{v:.10g}" for v in y]
    names = list(cols)
    lines = [",".join(names)] + [",".join(row) for row in zip(*(cols[c] for c in names))]
    path.write_text("\n".join(lines) + "\n")
    return [o.name for o in rec.plant.outputs if len(set(cols[o.name])) == 1]


def bindings(rec: Realised, constant=()) -> tuple[list[str], list[str]]:
    """``NAME=COLUMN:UNIT`` bindings of the inputs and the measured outputs but the `constant` ones."""
    return ([f"{i.name}={i.name}:{i.unit}" for i in rec.plant.inputs],
            [f"{o.name}={o.name}:{o.unit}" for o in rec.plant.outputs if o.name not in constant])


def score_case(rec: Realised, report, detuned: dict | None = None) -> Score:
    """Compare the diagnosis `report` (its JSON form) with the truth of `rec`.  With `detuned` (a
    nominal detuned by :func:`~diagnosis.benchmark.detune.detuned_nominal`), the answers but the
    ``nominal_value`` ones are scored and whether one of those refitted the detuned value is noted."""
    spec, eff = rec.spec, rec.effect
    s = Score(spec.label, spec.plant, rec.plant.model, spec.kind,
              "" if eff is None else eff.place, change=rec.change, ratio=spec.ratio,
              nominal_drifts=rec.nominal_drifts, drifting_plant=rec.plant.drifts)
    data = report if isinstance(report, dict) else report.to_json()
    found = [e for e in data.get("missing_physics", []) if e.get("kind", "none") != "none"]
    s.answers = [f"{e['kind']} @ {e['attached_to']}" for e in found]
    if detuned:
        s.detuned = dict(detuned)
        value = [e for e in found if e["kind"] == "nominal_value"]
        beside = _junctions_of(rec.plant.model, detuned.get("element"))
        # a value answer names the detuned value, or lists it as not told apart from its own (two
        # inertias geared together: one's value is the other's rescaled)
        s.detuned_named = any(detuned["parameter"] in e.get("parameters", {}) or _reads_as_value(e, beside)
                              for e in value)
        # where no value answered names it, the first answer that is the value read another way
        # stands for it (then it is no answer to the concealed effect)
        reading = None if s.detuned_named else next(
            (e for e in found if e not in value and _reads_as_value(e, beside)), None)
        s.detuned_named = s.detuned_named or reading is not None
        found = [e for e in found if e not in value and e is not reading]
    s.judge = str(data.get("fit", {}).get("judge", ""))
    s.answer_kind = found[0]["kind"] if found else "none"
    s.answer_place = found[0]["attached_to"] if found else ""
    s.parameters = {k: v for e in found for k, v in e.get("parameters", {}).items()}
    s.indistinguishable = [a["kind"] for a in found[0].get("indistinguishable", [])] if found else []
    if eff is None:
        s.kind_ok = s.place_ok = s.kind_or_indistinguishable_ok = not found
        s.affected = ""
        return s
    s.kind_ok = s.answer_kind == spec.kind
    s.place_ok = s.answer_place in eff.accepted_places()
    if (s.answer_kind, s.answer_place) in eff.equivalent_answers():     # one answer in two words
        s.kind_ok = s.place_ok = True
    s.kind_or_indistinguishable_ok = s.kind_ok or spec.kind in s.indistinguishable
    s.affected = rec.affected
    also = getattr(rec, "also", None)          # a compound case's second effect (a Realised)
    if also is not None:
        s.also_kind, s.also_place = also.spec.kind, also.effect.place
        first = rec.effect.effects[0]
        s.first_found = _names(found, spec.kind, first.accepted_places(), first.equivalent_answers())
        s.also_found = _names(found, s.also_kind, also.effect.accepted_places(), also.effect.equivalent_answers())
        s.first_visible, s.also_visible = rec.visible or (float("nan"), float("nan"))
    nom, imp = data["fit"]["nominal"].get(rec.affected), data["fit"]["improved"].get(rec.affected)
    if nom is not None and imp is not None:
        s.nominal_nrmse, s.improved_nrmse = float(nom), float(imp)
        s.improvement = 1.0 - float(imp) / float(nom) if nom > 0 else float("nan")
    return s


def _junctions_of(model: str, element) -> set:
    """The junction places (``"junction <name>"``) bonded to `element` of library `model`."""
    from plants import load
    graph = load(model)
    if element not in graph.elements:
        return set()
    return {f"junction {b.tail.element if end == 'head' else b.head.element}" for b, end in graph.bonds_of(element)}


def _reads_as_value(effect: dict, junctions: set) -> bool:
    """Whether the answered `effect` (report JSON) may be, by the report's own account, the detuned
    element's value: it lists a ``nominal_value`` at one of `junctions`, those bonded to that
    element (:func:`_junctions_of`), as not told apart from it (a force-driven carriage's input
    gain is its mass's value rescaled, :mod:`diagnosis.equivalent_readings`; seed 4401, case 007,
    answered its 13 % light mass as a gain of 0.874 on the force, then the concealed velocity
    sensor's offset)."""
    return any(a.get("kind") == "nominal_value" and a.get("place") in junctions
               for a in effect.get("indistinguishable", []))


def _names(found: list, kind: str, places: set, equivalents: set = frozenset()) -> bool:
    """Whether one of the answered effects `found` (report JSON) names `kind` at one of `places`,
    or lists `kind` at one of them as not told apart from its own (the alternative's place, which
    may differ from the answer's: a constant force on a cylinder's piston whose force is measured
    is a force sensor's offset, seed 6767's compound case 012), or is one of its `equivalents`
    (``(kind, place)`` pairs no recording tells apart from it: ``TruthEffect.equivalent_answers``)."""
    return any((e["kind"] == kind and e["attached_to"] in places) or (e["kind"], e["attached_to"]) in equivalents
               or any(a["kind"] == kind and (a.get("place") or e["attached_to"]) in places
                      for a in e.get("indistinguishable", []))
               for e in found)


def run_case(spec: CaseSpec, plants: dict, workdir: Path, *, max_effects: int = 2,
             second: CaseSpec | None = None, detune: float = 0.0, detune_kinds: str = "IC",
             sampling: float = 1.0) -> dict:
    """Realise, write, diagnose and score one case (with the `second` effect too: a compound case,
    :mod:`diagnosis.benchmark.compound`; against a nominal detuned by the fraction `detune`, an
    element of `detune_kinds` picked: :mod:`diagnosis.benchmark.detune`; recorded at a rate and for
    a duration scaled by factors drawn within `sampling`: :mod:`diagnosis.benchmark.sampling`);
    never raises (errors are scored)."""
    from ..diagnose import diagnose
    from .detune import detuned_nominal, stated_start
    from .sampling import resampled
    plant, drawn = resampled(plants[spec.plant](), spec.seed, sampling)
    nominal, detuned = detuned_nominal(plant.model, spec.seed, detune, detune_kinds)
    label = compound_label(spec, second)
    t0 = time.perf_counter()
    try:
        rec = realise(spec, plant) if second is None else realise_compound(spec, second, plant)
    except Exception as exc:   # a generator failure is the benchmark's, reported, not scored
        return {"label": label, "generator_error": f"{type(exc).__name__}: {exc}"}
    path = Path(workdir) / f"{label}.csv"
    constant = write_csv(rec, path, np.random.default_rng(spec.seed + 1))
    if len(constant) == len(rec.plant.outputs):
        return {"label": label, "generator_error": f"every output is constant in the recording ({constant})"}
    t1 = time.perf_counter()
    # a user binds the outputs that were measured varying (the diagnosis refuses a constant one)
    ins, outs = bindings(rec, constant)
    try:
        # the recording starts where the plant rests, which a user states (diagnose's x0) in
        # their own model's terms
        report = diagnose(nominal, str(path), inputs=ins, outputs=outs, max_effects=max_effects,
                          x0=stated_start(plant.nominal_x0, nominal, detuned))
        score = score_case(rec, report, detuned)
    except Exception as exc:
        score = score_case(rec, {"missing_physics": [], "fit": {"nominal": {}, "improved": {}}}, detuned)
        score.kind_ok = score.place_ok = score.kind_or_indistinguishable_ok = False
        score.answer_kind = "error"
        score.error = f"{type(exc).__name__}: {exc}"
        score.error += "\n" + traceback.format_exc(limit=3) if not hasattr(exc, "args") else ""
    score.seconds_generate, score.seconds_diagnose = t1 - t0, time.perf_counter() - t1
    score.glitches = sum(len(samples) for samples, _ in glitches(rec).values())
    score.label = label
    out = asdict(score)
    out["spec"] = asdict(spec)
    out["effect"] = None if rec.effect is None else rec.effect.describe()
    out["sigma"], out["quantum"] = rec.sigma, rec.quantum
    out["calibration_runs"] = rec.calibration_runs
    if drawn:
        out["sampling"] = drawn
    return json.loads(json.dumps(out, default=float))
