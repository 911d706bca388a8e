"""A sweep's specification: what to run, what to vary, what to keep -- typed data, and its loader.

A spec file (TOML or YAML) holds the same keys as :class:`SweepSpec`; either a
scenario (``reproductions``) or a model (a bond graph simulated open loop)::

    name = "ukf-robustness"
    scenario = "pam-ukf"            # bondcosim cosim --list
    quick = true                    # the scenario's shortened run
    samples = 200                   # draws (per grid point)
    seed = 1
    metrics = ["ukf.angle.I", "model_only.angle.I"]   # default: every numeric result
    [vary]
    A1 = "normal(1, 0.1)*nominal"   # sweeps.distributions
    c_s = "uniform(0.8, 1.2)*nominal"
    [fixed]
    segment_s = 1.0

    # or, instead of ``scenario``:
    [model]
    name = "mass-spring-damper"     # built-in name or .json graph file
    stop_time = 20.0                # s
    output_interval = 0.01          # s
    inputs = { F = "1" }            # number or expression of t
    outputs = ["x"]                 # time series stored with each run

A model's metrics are statistics of its outputs: ``x.final``, ``x.mean``,
``x.min``, ``x.max``, ``x.rms``, ``x.std`` (unit of ``x``).
"""
from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Mapping

from .distributions import Grid, parse
from .errors import DistributionError, SpecError

__all__ = ["ScenarioTarget", "ModelTarget", "SweepSpec", "load_spec", "spec_from_dict", "OUTPUT_STATS"]

#: Statistics of a model output available as metrics (``OUTPUT.STAT``).
OUTPUT_STATS = ("final", "mean", "min", "max", "rms", "std")


@dataclass(frozen=True)
class ScenarioTarget:
    """A closed-loop scenario of :mod:`reproductions` run once per sweep point.

    Attributes
    ----------
    name : str
        e.g. ``"pam-ukf"``.
    quick : bool
        The scenario's shortened run.
    """

    name: str
    quick: bool = False


@dataclass(frozen=True)
class ModelTarget:
    """A bond-graph model simulated open loop once per sweep point.

    Attributes
    ----------
    model : str
        Built-in model name or ``.json`` graph file.
    stop_time : float, s
    inputs : mapping str -> float or str
        Input values or expressions of ``t``.
    output_interval : float, s, optional
    outputs : tuple of str
        Outputs whose time series are stored with each run (column ``output.NAME``, and ``output.t``).
    """

    model: str
    stop_time: float
    inputs: Mapping = field(default_factory=dict)
    output_interval: float | None = None
    outputs: tuple = ()


@dataclass(frozen=True)
class SweepSpec:
    """What a sweep runs.

    Runs: the Cartesian product of the :class:`~sweeps.distributions.Grid`
    parameters, each point repeated `samples` times with fresh draws of the
    :class:`~sweeps.distributions.Distribution` parameters.  Run ``i`` draws
    from ``numpy.random.default_rng(SeedSequence(seed, spawn_key=(i,)))``, so a
    run's values and its own seed (the scenario's noise) depend on ``(seed, i)``
    only -- not on chunking, workers or resumption.

    Attributes
    ----------
    target : ScenarioTarget or ModelTarget
    vary : mapping str -> Distribution or Grid
    fixed : mapping str -> float
        Parameter values (SI) for every run.
    samples : int
        Runs per grid point (>= 1).
    seed : int
    metrics : tuple of str
        Kept metrics; empty: every numeric one.
    name : str
    """

    target: ScenarioTarget | ModelTarget
    vary: Mapping = field(default_factory=dict)
    fixed: Mapping = field(default_factory=dict)
    samples: int = 1
    seed: int = 0
    metrics: tuple = ()
    name: str = "sweep"

    def __post_init__(self):
        object.__setattr__(self, "vary", MappingProxyType(dict(self.vary)))
        object.__setattr__(self, "fixed", MappingProxyType({k: float(v) for k, v in dict(self.fixed).items()}))
        object.__setattr__(self, "metrics", tuple(self.metrics))

    @property
    def grid_names(self) -> tuple:
        """Names of the grid-varied parameters, in order."""
        return tuple(n for n, law in self.vary.items() if isinstance(law, Grid))

    def to_dict(self) -> dict:
        """JSON-ready; :func:`spec_from_dict` reads it back (the store keeps it to check ``--resume``)."""
        target = self.target
        out = {"name": self.name, "samples": self.samples, "seed": self.seed, "metrics": list(self.metrics),
               "vary": {n: law.text for n, law in self.vary.items()}, "fixed": dict(self.fixed)}
        if isinstance(target, ScenarioTarget):
            out.update(scenario=target.name, quick=target.quick)
        else:
            out["model"] = {"name": target.model, "stop_time": target.stop_time, "inputs": dict(target.inputs),
                            "output_interval": target.output_interval, "outputs": list(target.outputs)}
        return out


_KEYS = {"name", "scenario", "quick", "model", "samples", "seed", "metrics", "vary", "fixed"}
_MODEL_KEYS = {"name", "stop_time", "inputs", "output_interval", "outputs"}


def _number(problems, where, value, *, positive=False, whole=False):
    if isinstance(value, bool) or not isinstance(value, (int, float)) or (whole and int(value) != value):
        problems.append(f"{where}: {value!r} is not a {'whole ' if whole else ''}number")
        return None
    if positive and not value > 0:
        problems.append(f"{where}: {value!r} must be > 0")
        return None
    return int(value) if whole else float(value)


def _target(data, problems):
    if ("scenario" in data) == ("model" in data):
        problems.append("give exactly one of 'scenario' (a name) and 'model' (a table)")
        return None
    if "scenario" in data:
        if not isinstance(data["scenario"], str):
            problems.append(f"scenario: {data['scenario']!r} is not a name")
            return None
        return ScenarioTarget(data["scenario"], bool(data.get("quick", False)))
    m = data["model"]
    if not isinstance(m, dict):
        problems.append("model: must be a table with name, stop_time, inputs, output_interval, outputs")
        return None
    problems.extend(f"model: unknown key {k!r}; known keys are {', '.join(sorted(_MODEL_KEYS))}"
                    for k in sorted(set(m) - _MODEL_KEYS))
    if "quick" in data:
        problems.append("quick: applies to scenarios only")
    name, stop = m.get("name"), _number(problems, "model.stop_time", m.get("stop_time"), positive=True)
    if not isinstance(name, str):
        problems.append("model.name: missing (a built-in model name or a .json graph file)")
    interval = m.get("output_interval")
    if interval is not None:
        interval = _number(problems, "model.output_interval", interval, positive=True)
    inputs = m.get("inputs", {})
    if not isinstance(inputs, dict):
        problems.append("model.inputs: must be a table NAME = value or expression")
        inputs = {}
    outputs = m.get("outputs", [])
    if not isinstance(outputs, list) or not all(isinstance(o, str) for o in outputs):
        problems.append("model.outputs: must be a list of output names")
        outputs = []
    if not isinstance(name, str) or stop is None:
        return None
    return ModelTarget(name, stop, {str(k): v for k, v in inputs.items()}, interval, tuple(outputs))


def spec_from_dict(data, *, source: str = "spec") -> SweepSpec:
    """Build a :class:`SweepSpec` from plain data (a parsed spec file), checking every key.

    Raises
    ------
    SpecError
        Every problem found, each naming its key (unknown keys, missing target,
        bad numbers, unreadable distributions).
    """
    if not isinstance(data, dict):
        raise SpecError(source, [f"the top level must be a table of keys, found {type(data).__name__}"])
    problems = [f"unknown key {k!r}; known keys are {', '.join(sorted(_KEYS))}" for k in sorted(set(data) - _KEYS)]
    target = _target(data, problems)
    samples = _number(problems, "samples", data.get("samples", 1), positive=True, whole=True)
    seed = _number(problems, "seed", data.get("seed", 0), whole=True)
    vary, fixed = {}, {}
    for key, store in (("vary", vary), ("fixed", fixed)):
        table = data.get(key, {})
        if not isinstance(table, dict):
            problems.append(f"{key}: must be a table NAME = ...")
            continue
        for n, text in table.items():
            if key == "fixed":
                value = _number(problems, f"fixed.{n}", text)
                if value is not None:
                    store[str(n)] = value
                continue
            try:
                store[str(n)] = parse(str(n), text)
            except DistributionError as exc:
                problems.append(f"vary.{n}: {exc}")
    for n in sorted(set(vary) & set(fixed)):
        problems.append(f"{n}: both varied and fixed")
    metrics = data.get("metrics", [])
    if not isinstance(metrics, list) or not all(isinstance(m, str) for m in metrics):
        problems.append("metrics: must be a list of metric names")
        metrics = []
    name = data.get("name", "sweep")
    if problems or target is None:
        raise SpecError(source, problems or ["no target"])
    return SweepSpec(target, vary, fixed, samples, seed, tuple(metrics), str(name))


def load_spec(path) -> SweepSpec:
    """Read a sweep spec file: ``.toml`` or ``.yaml``/``.yml`` (the module docstring shows the keys).

    Raises
    ------
    SpecError
        Missing or unreadable file, a syntax error (with the parser's message), or bad keys.
    """
    path = Path(path)
    if path.suffix not in (".toml", ".yaml", ".yml", ".json"):
        raise SpecError(path, [f"unknown spec format {path.suffix!r}; expected .toml, .yaml, .yml or .json"])
    try:
        text = path.read_text()
    except OSError as exc:
        raise SpecError(path, [f"cannot read the file: {exc.strerror or exc}"]) from None
    try:
        if path.suffix == ".toml":
            import tomllib
            data = tomllib.loads(text)
        elif path.suffix == ".json":
            data = json.loads(text)
        else:
            import yaml
            data = yaml.safe_load(text)
    except Exception as exc:  # the parsers' own errors: report them in one line, with the file
        raise SpecError(path, [f"not valid {path.suffix[1:].upper()}: {exc}"]) from None
    return spec_from_dict(data, source=str(path))
