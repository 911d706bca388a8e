"""Recording generator: commands -> truth model -> sensors -> CSV, plus the manifest.

Deterministic: one ``numpy.random.default_rng(case.seed)`` draws, in this order,
the excitation (``case.excite``) and then the noise of each output in the
order of ``case.outputs``.  The commands are quantised to the DAC resolution and
written with the column's decimals; the model is driven by exactly the values
read back from those texts, as zero-order-hold tables, so a diagnosis that
reads the CSV drives the nominal model with the same inputs.
"""
from __future__ import annotations

import json
from functools import lru_cache
from pathlib import Path

import numpy as np

import plants.library as library
from bondgraph.numerics import simulate

from .definitions import CASES, Case
from ..errors import DiagnosisError

__all__ = ["sample_times", "commands", "simulate_case", "GeneratedRecording", "record", "write_case",
           "manifest_entry", "write_all", "effect_ratio", "MANIFEST", "HOLDOUT"]

#: File name of the manifest next to the CSV files.
MANIFEST = "cases.json"


def sample_times(case: Case) -> np.ndarray:
    """The sample instants, s: ``k / rate`` for ``k = 0 .. duration * rate``."""
    n = int(round(case.duration * case.rate)) + 1
    return np.arange(n) / case.rate


def _fmt(values, decimals: int) -> list[str]:
    # rounding first (+ 0.0 turns -0.0 into 0.0) so that no "-0.000" is written
    rounded = np.round(np.asarray(values, dtype=float), decimals) + 0.0
    return [f"{v:.{decimals}f}" for v in rounded]


def commands(case: Case, t: np.ndarray, rng: np.random.Generator) -> tuple[dict, dict]:
    """Column texts and model-unit commands of the inputs.

    Returns
    -------
    texts : dict column -> list of str
    model : dict input name -> ndarray, model unit (the column texts read back / scale)
    """
    raw = case.excite(t, rng)
    texts, model = {}, {}
    for s in case.inputs:
        col = np.round(np.asarray(raw[s.name]) * s.scale / s.quantum) * s.quantum
        texts[s.column] = _fmt(col, s.decimals)
        model[s.name] = np.array([float(x) for x in texts[s.column]]) / s.scale
    return texts, model


def _compressed(times: np.ndarray, values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The same zero-order-hold table, keeping only the samples where the value changes."""
    keep = np.concatenate(([True], np.diff(values) != 0))
    return times[keep], values[keep]


@lru_cache(maxsize=32)
def _equations(model: str, effect):
    """State equations of the nominal `model` with the structure of `effect` (a frozen, hashable
    :meth:`Effect.structure`, or None) added, derived once per process (the derivation, not
    the simulation, is the slow part); the effect's values are passed at simulation time."""
    graph = library.build(model)
    return (graph if effect is None else effect.graph(graph)).equations()


def simulate_case(case: Case, t: np.ndarray, model_commands: dict, *, truth: bool = True,
                  effect=None) -> dict[str, np.ndarray]:
    """Noise-free outputs (model units) at `t` of the truth (or the nominal) model.

    Parameters
    ----------
    case : Case
    t : ndarray, shape (n,), s
        Sample times (uniform).
    model_commands : dict str -> ndarray, shape (n,)
        Input commands in the model's units (zero-order hold).
    truth : bool
        False: the nominal model on the commands, no sensor effect.
    effect : Effect, optional
        Replaces ``case.effect`` (e.g. its ``neutral()`` form).
    """
    effect = case.effect if effect is None else effect
    tables = {k: (np.asarray(t, float), np.asarray(v, float)) for k, v in model_commands.items()}
    if truth and effect is not None:
        tables = effect.inputs(t, model_commands)
    tables = {k: _compressed(*tv) for k, tv in tables.items()}
    with_effect = truth and effect is not None
    eqs = _equations(case.model, effect.structure() if with_effect else None)
    result = simulate(eqs, (float(t[0]), float(t[-1])), inputs=tables,
                      params=effect.simulation_params() if with_effect else None,
                      output_interval=float(t[1] - t[0]))
    if len(result.t) != len(t) or not np.allclose(result.t, t, atol=1e-9):
        raise DiagnosisError(f"case {case.name}: the simulation's time grid does not match the samples")
    outputs = {s.name: np.asarray(result[s.name], dtype=float) for s in case.outputs}
    if truth and effect is not None:
        outputs = effect.outputs(outputs)
    return outputs


class GeneratedRecording:
    """A generated recording: column texts (the CSV) and the noise-free signals behind it.

    Attributes
    ----------
    case : Case
    t : ndarray, s
    texts : dict column -> list of str
        Every column as written (time first).
    commands : dict input -> ndarray, model unit
    clean : dict output -> ndarray, model unit
        Truth-model outputs before the sensors' noise and quantisation.
    """

    def __init__(self, case, t, texts, commands, clean):
        self.case, self.t, self.texts, self.commands, self.clean = case, t, texts, commands, clean

    def csv(self) -> str:
        """The CSV text: header, then one row per sample."""
        cols = list(self.texts)
        rows = [",".join(cols)] + [",".join(r) for r in zip(*(self.texts[c] for c in cols))]
        return "\n".join(rows) + "\n"


def record(case: Case) -> GeneratedRecording:
    """Generate `case`'s recording (deterministic, see the module docstring)."""
    rng = np.random.default_rng(case.seed)
    t = sample_times(case)
    dt_decimals = max(3, int(np.ceil(np.log10(case.rate))))
    texts = {case.time_column: _fmt(t, dt_decimals)}
    input_texts, model_commands = commands(case, t, rng)
    texts.update(input_texts)
    clean = simulate_case(case, t, model_commands)
    for s in case.outputs:
        noisy = s.scale * clean[s.name] + rng.normal(0.0, s.sigma, size=len(t))
        texts[s.column] = _fmt(np.round(noisy / s.quantum) * s.quantum, s.decimals)
    return GeneratedRecording(case, t, texts, model_commands, clean)


def write_case(case: Case, outdir) -> tuple[Path, GeneratedRecording]:
    """Write ``<outdir>/<case.name>.csv``; return its path and the recording."""
    rec = record(case)
    path = Path(outdir) / f"{case.name}.csv"
    path.write_text(rec.csv())
    return path, rec


#: Fraction of the span, at the end, over which the held-out effect size is documented
#: (the diagnosis' default hold-out).
HOLDOUT = 0.3


def effect_ratio(case: Case, rec: GeneratedRecording, *, holdout: float | None = None) -> float:
    """RMS(truth - nominal) of the affected output over its effective noise sigma (both noise-free),
    over the whole record or over its last `holdout` fraction of the time span."""
    s = case.output(case.affected)
    nominal = simulate_case(case, rec.t, rec.commands, truth=False)[case.affected]
    diff = s.scale * (rec.clean[case.affected] - nominal)
    if holdout is not None:
        diff = diff[rec.t >= rec.t[-1] - holdout * (rec.t[-1] - rec.t[0])]
    return float(np.sqrt(np.mean(diff ** 2)) / s.effective_sigma)


def manifest_entry(case: Case, rec: GeneratedRecording) -> dict:
    """The manifest's record of `case` (see ``diagnosis.cases`` for the fields)."""
    graph = library.build(case.model)
    units = {d.name: d.unit for d in graph.inputs()} | {o.name: o.unit for o in graph.outputs.values()}
    effect = case.effect
    entry = {
        "name": case.name, "file": f"{case.name}.csv", "model": case.model,
        "description": case.description, "kind": case.kind,
        "place": None if effect is None else {"kind": effect.place.kind, "name": effect.place.name},
        "parameters": {} if effect is None else
        {p.name: {"value": p.value, "unit": p.unit, "description": p.description} for p in effect.params},
        "equivalent_places": [{"kind": q.kind, "name": q.name} for q in case.equivalent],
        "equivalence": case.equivalence,
        "affected_output": case.affected,
        "time": case.time_column,
        "inputs": [s.binding for s in case.inputs],
        "outputs": [s.binding for s in case.outputs],
        "model_units": {s.name: units[s.name] for s in case.inputs + case.outputs},
        "seed": case.seed, "sample_rate_Hz": case.rate, "duration_s": case.duration,
        "excitation": case.excitation,
        "noise": {s.name: {"column": s.column, "unit": s.unit, "sigma": s.sigma, "quantum": s.quantum,
                           "effective_sigma": round(s.effective_sigma, 6)} for s in case.outputs},
        "min_effect_to_noise": case.min_ratio,
    }
    if effect is not None:
        entry["effect_to_noise"] = round(effect_ratio(case, rec), 2)
        entry["holdout_effect_to_noise"] = round(effect_ratio(case, rec, holdout=HOLDOUT), 2)
    return entry


def write_all(outdir, cases=CASES, *, progress: bool = False) -> dict:
    """Write every case's CSV and the manifest ``cases.json`` into `outdir`; return the manifest."""
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    entries = []
    for c in cases:
        if progress:
            print(f"  {c.name} ...", flush=True)
        _, rec = write_case(c, outdir)
        entries.append(manifest_entry(c, rec))
    manifest = {"generator": "python -m diagnosis.cases OUTDIR (diagnosis/cases/generate.py)",
                "cases": entries}
    (outdir / MANIFEST).write_text(json.dumps(manifest, indent=1) + "\n")
    return manifest
