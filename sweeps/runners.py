"""What one run of a sweep does, as a picklable object built once and shipped to every worker.

A runner is made on the client from a :class:`~sweeps.spec.SweepSpec`
(:func:`make_runner`), checks every name there, builds what is costly once
(:meth:`prepare`: a scenario's FMUs, a model's derived state equations) and
is then shipped to each worker once; a worker calls it for each run:
``runner(params, seed) -> {metric: value}``.

What is cheap to ship, and so shipped instead of rebuilt:

- an FMU: a zip of some 16 kB (the ``pam`` rig) holding its compiled binary;
  a worker writes it once into its own temporary directory (by content hash)
  and every run sets its parameters on it before initialisation;
- a model's :class:`~bondgraph.equations.StateEquations` (some 17 kB,
  cloudpickled): deriving them takes ~1 s (``pam``);
- the compiled C libraries (the model's evaluator, the UKF's kernels, the FMU
  fast path; 15-29 kB each): :meth:`prepare` runs the target once on the
  client with its nominal values while :func:`bondgraph.numerics.c_shipped.recording`
  notes every library built or loaded, and ships their bytes as a
  :class:`~bondgraph.numerics.c_shipped.KernelBundle`.  A worker installs the bundle
  before its first run, so it loads those libraries without generating code
  or needing a compiler; a library the bundle lacks is compiled there as before.
"""
from __future__ import annotations

import hashlib
import itertools
import os
import socket
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .distributions import Distribution, Grid
from .errors import MetricError, SpecError
from .spec import OUTPUT_STATS, ModelTarget, ScenarioTarget, SweepSpec

__all__ = ["RunSpec", "ScenarioRunner", "ModelRunner", "make_runner", "plan_runs", "run_chunk", "flatten"]


@dataclass(frozen=True)
class RunSpec:
    """One run: its index, the values of the varied parameters (SI) and its own seed."""

    run_id: int
    params: dict
    seed: int


def flatten(result, prefix: str = "") -> dict:
    """The numeric leaves of a nested result dict, keys joined by ``.`` (``ukf.angle.I``).

    Examples
    --------
    >>> flatten({"ukf": {"angle": {"I": 0.4}}, "units": {"angle": "deg"}, "ok": True, "w": [1, 2]})
    {'ukf.angle.I': 0.4, 'ok': True}
    """
    out = {}
    for key, value in result.items():
        if isinstance(value, dict):
            out.update(flatten(value, f"{prefix}{key}."))
        elif isinstance(value, (bool, np.bool_)):
            out[f"{prefix}{key}"] = bool(value)
        elif isinstance(value, (int, float, np.integer, np.floating)) and value is not None:
            out[f"{prefix}{key}"] = float(value)
    return out


def _select(metrics: dict, keep, target: str) -> dict:
    if not keep:
        return metrics
    missing = [k for k in keep if k not in metrics]
    if missing:
        raise MetricError(missing[0], metrics, target)
    return {k: metrics[k] for k in keep}


def _record_kernels(run):
    """The C libraries that `run()` builds or loads, as a KernelBundle (bondgraph.numerics.c_shipped).

    `run` is one run with nominal values; if it fails, what it built so far is
    kept and the sweep's own runs report the failure -- except a MetricError,
    which every run would raise, so it stops the sweep before any cluster starts.
    """
    from bondgraph.numerics import c_shipped
    with c_shipped.recording() as rec:
        try:
            run()
        except MetricError:
            raise
        except Exception:  # noqa: BLE001 -- reported by the runs themselves, each as a failed row
            pass
    return rec.bundle()


def _install(kernels) -> None:
    if kernels is not None:
        kernels.install()          # once per process: later calls return at once


def _check_names(problems, spec: SweepSpec, known: dict, target: str) -> None:
    for where, names in (("vary", spec.vary), ("fixed", spec.fixed)):
        for n in names:
            if n not in known:
                problems.append(f"{where}.{n}: {target} has no parameter {n!r}; known parameters are "
                                f"{', '.join(known) or '(none)'}")


class ScenarioRunner:
    """Runs one closed-loop scenario of :mod:`reproductions` per call.

    Parameters
    ----------
    spec : SweepSpec
        With a :class:`~sweeps.spec.ScenarioTarget`.

    Attributes
    ----------
    nominal : dict str -> float
        Every parameter's default (SI), for ``*nominal`` laws.
    units : dict str -> str
    """

    #: Typical run time, s (``pam-ukf`` quick: 0.3-0.5 s), for the chunk size (:mod:`sweeps.engine`).
    run_time_hint_s = 0.5

    def __init__(self, spec: SweepSpec):
        import reproductions as scenarios
        self.target = spec.target
        self.label = f"scenario {self.target.name!r}"
        table = scenarios.parameters(self.target.name)      # UnknownNameError lists the scenarios
        if not table:
            able = [n for n in scenarios.names() if scenarios.parameters(n)]
            raise SpecError(spec.name, [f"scenario: {self.label} takes no parameters, seed or prebuilt FMUs, so "
                                        f"it cannot be swept; scenarios that can: {', '.join(able)}"])
        problems = []
        _check_names(problems, spec, table, self.label)
        if problems:
            raise SpecError(spec.name, problems)
        self.nominal = {n: p.value for n, p in table.items()}
        self.units = {n: p.unit for n, p in table.items()}
        self.fixed = dict(spec.fixed)
        self.keep = tuple(spec.metrics)
        self.fmus: dict = {}
        self.kernels = None

    def prepare(self, *, ship_kernels: bool = True) -> None:
        """Export the scenario's FMUs once, keeping their bytes (shipped with the runner).

        With `ship_kernels`, also run the scenario once (quick profile, fixed
        values, seed 0) and keep the C libraries it used (:func:`_record_kernels`;
        ~0.5 s for ``pam-ukf``).  A requested metric the results lack stops here.
        """
        import reproductions as scenarios
        with tempfile.TemporaryDirectory() as tmp:
            files = scenarios.export_fmus(self.target.name, tmp)
            self.fmus = {Path(p).name: Path(p).read_bytes() for p in files.values()}
        if ship_kernels:
            self.kernels = _record_kernels(lambda: self._run({}, 0, quick=True))

    def __call__(self, params: dict, seed: int) -> dict:
        """One scenario run; its numeric results flattened (:func:`flatten`), kept metrics only."""
        _install(self.kernels)
        return self._run(params, seed, quick=self.target.quick)

    def _run(self, params: dict, seed: int, *, quick: bool) -> dict:
        import reproductions as scenarios
        result = scenarios.run(self.target.name, quick=quick, params={**self.fixed, **params},
                               seed=seed, fmu_dir=_local_files(self.fmus))
        return _select(flatten(result), self.keep, self.label)


class ModelRunner:
    """Simulates a bond-graph model open loop per call (:func:`bondgraph.numerics.simulation.simulate`).

    Metrics are statistics of every output (``NAME.final``, ``.mean``, ``.min``,
    ``.max``, ``.rms``, ``.std``, the output's unit); the outputs named in the
    target are also returned as time series (``output.NAME``, ``output.t``).
    The model is deterministic: the run's seed is recorded but not used.

    Parameters
    ----------
    spec : SweepSpec
        With a :class:`~sweeps.spec.ModelTarget`.
    graph : BondGraph or StateEquations, optional
        The model already loaded (the CLI passes its own loader's); default:
        the target's built-in name or ``.json`` file.
    """

    #: Typical run time, s (a textbook model), for the chunk size (:mod:`sweeps.engine`).
    run_time_hint_s = 0.03

    def __init__(self, spec: SweepSpec, graph=None):
        target = self.target = spec.target
        self.label = f"model {target.model!r}"
        self.eqs = _equations(target.model, graph)
        problems = []
        _check_names(problems, spec, self.eqs.param_values, self.label)
        outputs = list(self.eqs.outputs)
        problems.extend(f"model.outputs: {self.label} has no output {o!r}; its outputs are {', '.join(outputs)}"
                        for o in target.outputs if o not in outputs)
        problems.extend(f"model.inputs: {self.label} has no input {i!r}; its inputs are "
                        f"{', '.join(self.eqs.input_names) or '(none)'}"
                        for i in target.inputs if i not in self.eqs.input_names)
        known = [f"{o}.{s}" for o in outputs for s in OUTPUT_STATS]
        problems.extend(f"metrics: {self.label} has no metric {m!r}; its metrics are OUTPUT.STAT with OUTPUT "
                        f"in {', '.join(outputs)} and STAT in {', '.join(OUTPUT_STATS)}"
                        for m in spec.metrics if m not in known)
        if problems:
            raise SpecError(spec.name, problems)
        self.nominal = dict(self.eqs.param_values)
        self.units = {n: str(self.eqs.units.get(n, "")) for n in self.nominal}
        self.fixed = dict(spec.fixed)
        self.keep = tuple(spec.metrics)
        self.kernels = None

    def prepare(self, *, ship_kernels: bool = True) -> None:
        """The equations were derived in the constructor; with `ship_kernels`, simulate the
        model once with its nominal values and keep the C libraries it used (:func:`_record_kernels`)."""
        if ship_kernels:
            self.kernels = _record_kernels(lambda: self({}, 0))

    def __call__(self, params: dict, seed: int) -> dict:
        """One open-loop simulation: the output statistics (and series) of :class:`ModelRunner`."""
        from bondgraph.numerics.simulation import simulate
        _install(self.kernels)
        t = self.target
        res = simulate(self.eqs, (0.0, t.stop_time), inputs=dict(t.inputs), params={**self.fixed, **params},
                       output_interval=t.output_interval)
        metrics = {}
        for o in self.eqs.outputs:
            y = np.asarray(res[o], dtype=float)
            stats = {"final": y[-1], "mean": np.mean(y), "min": np.min(y), "max": np.max(y),
                     "rms": np.sqrt(np.mean(y * y)), "std": np.std(y)}
            metrics.update({f"{o}.{k}": float(v) for k, v in stats.items()})
        out = _select(metrics, self.keep, self.label)
        if t.outputs:
            out["output.t"] = np.asarray(res.t, dtype=float).tolist()
            out.update({f"output.{o}": np.asarray(res[o], dtype=float).tolist() for o in t.outputs})
        return out


def _equations(model: str, graph):
    if graph is not None:
        return graph if hasattr(graph, "param_values") else graph.equations()
    from plants import load as load_model
    return load_model(model).equations()


def make_runner(spec: SweepSpec, *, graph=None):
    """The runner of `spec`'s target, every name checked (:class:`ScenarioRunner` or :class:`ModelRunner`).

    Raises
    ------
    SpecError
        Unknown parameters, outputs, inputs or metrics (all listed).
    UnknownNameError, GraphError
        Unknown scenario or model.
    """
    if isinstance(spec.target, ScenarioTarget):
        return ScenarioRunner(spec)
    if isinstance(spec.target, ModelTarget):
        return ModelRunner(spec, graph)
    raise SpecError(spec.name, [f"target: {spec.target!r} is neither a scenario nor a model"])


def plan_runs(spec: SweepSpec, nominal: dict) -> list:
    """Every run of `spec`, in order (see :class:`~sweeps.spec.SweepSpec` for the seeding).

    Parameters
    ----------
    nominal : dict str -> float
        The parameters' defaults, for ``*nominal`` laws.

    Returns
    -------
    list of RunSpec
    """
    grid = [n for n, law in spec.vary.items() if isinstance(law, Grid)]
    random = [n for n, law in spec.vary.items() if isinstance(law, Distribution)]
    axes = [spec.vary[n].values(nominal=nominal[n]) for n in grid]
    runs = []
    for point in itertools.product(*axes):
        for _ in range(spec.samples):
            run_id = len(runs)
            rng = np.random.default_rng(np.random.SeedSequence(spec.seed, spawn_key=(run_id,)))
            params = dict(zip(grid, point))
            params.update({n: spec.vary[n].sample(rng, nominal=nominal[n]) for n in random})
            runs.append(RunSpec(run_id, params, int(rng.integers(0, 2**31 - 1))))
    return runs


_LOCAL: dict = {}


def _local_files(files: dict):
    """A directory of this process holding `files` (name -> bytes), written once per content."""
    if not files:
        return None
    digest = hashlib.sha256(b"".join(n.encode() + b"\0" + files[n] for n in sorted(files))).hexdigest()[:16]
    if digest not in _LOCAL:
        tmp = tempfile.TemporaryDirectory(prefix=f"bondcosim-sweep-{digest}-")
        for name, data in files.items():
            Path(tmp.name, name).write_bytes(data)
        _LOCAL[digest] = tmp            # removed when the process ends
    return _LOCAL[digest].name


def run_chunk(runner, runs) -> list:
    """Run `runs` (RunSpecs) one after the other; one row per run, failures recorded, never raised.

    A run that raises (diverges, an FMU discards a step, a bad value) gives a
    row with ``status = "failed"`` and its error text; the chunk goes on.
    Only a :class:`~sweeps.errors.MetricError` (the spec asks for a metric the
    results do not have, true of every run) stops the sweep.

    Returns
    -------
    list of dict
        ``run_id``, ``status`` (``"ok"``/``"failed"``), ``error``, ``seed``,
        ``started`` (s since the epoch), ``duration_s`` (s), ``worker``
        (``host:pid``), ``param.NAME`` and ``metric.NAME`` (or ``output.NAME``) columns.
    """
    from bondgraph.numerics.threads import limited

    with limited(1):            # a worker has one core; the compiled loops must not share it out
        return _run_each(runner, runs)


def _run_each(runner, runs) -> list:
    worker = f"{socket.gethostname()}:{os.getpid()}"
    rows = []
    for run in runs:
        started, start = time.time(), time.perf_counter()
        status, error, metrics = "ok", "", {}
        try:
            metrics = runner(dict(run.params), run.seed)
        except MetricError:
            raise
        except Exception as exc:  # any failure of one run is recorded with its text; the sweep goes on
            status, error = "failed", f"{type(exc).__name__}: {exc}"[:4000]
        row = {"run_id": run.run_id, "status": status, "error": error, "seed": run.seed,
               "started": started, "duration_s": time.perf_counter() - start, "worker": worker}
        row.update({f"param.{k}": v for k, v in run.params.items()})
        row.update({(k if k.startswith("output.") else f"metric.{k}"): v for k, v in metrics.items()})
        rows.append(row)
    return rows
