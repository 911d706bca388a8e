"""Sweeps, Monte-Carlo and fleet diagnosis on Dask: many co-simulations, simulations or diagnoses.

The layer above :mod:`cosim` and :mod:`diagnosis` and below the application
(:mod:`bondcosim`): a spec says what to run (a closed-loop scenario or a
bond-graph model), what to vary (grids, random laws) and what to keep; the
engine runs it serially, on a local Dask cluster or on any Dask scheduler,
streaming one row per run to Parquet, and ends with plots.

Public names
------------
SweepSpec, ScenarioTarget, ModelTarget
    Typed specs (:mod:`sweeps.spec`); :func:`load_spec` reads TOML/YAML files.
Distribution, Grid, parse_law
    Laws and grids (:mod:`sweeps.distributions`).
run_sweep, montecarlo_spec, SweepResult
    Run a spec into a results directory (:mod:`sweeps.sweep`).
diagnose_batch, FleetResult
    One diagnosis per recording, and the fleet's summary (:mod:`sweeps.fleet`).
SweepError, SpecError, DistributionError, MetricError, StoreError, EngineError
    Errors (:mod:`sweeps.errors`).
"""
from __future__ import annotations

from .distributions import Distribution, Grid, parse as parse_law
from .errors import DistributionError, EngineError, MetricError, SpecError, StoreError, SweepError
from .spec import ModelTarget, ScenarioTarget, SweepSpec, load_spec, spec_from_dict
from .sweep import SweepResult, montecarlo_spec, run_sweep

__all__ = ["SweepSpec", "ScenarioTarget", "ModelTarget", "load_spec", "spec_from_dict", "Distribution", "Grid",
           "parse_law", "run_sweep", "montecarlo_spec", "SweepResult", "diagnose_batch", "FleetResult",
           "SweepError", "SpecError", "DistributionError", "MetricError", "StoreError", "EngineError"]


def __getattr__(name):
    # the fleet module imports diagnosis only when asked for
    if name in ("diagnose_batch", "FleetResult"):
        from . import fleet
        return getattr(fleet, name)
    raise AttributeError(f"module 'sweeps' has no attribute {name!r}")
