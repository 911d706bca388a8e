"""bondgraph.numerics: the state equations of :mod:`bondgraph` turned into numbers.

Code generation (:mod:`.codegen_c`, :mod:`.codegen_c_templates`, :mod:`.c_build`),
compiled and numpy evaluation (:func:`compile_model`, :mod:`.evaluate_c`,
:mod:`.evaluate_numpy`, :mod:`.evaluate_samples`), simulation (:func:`simulate`,
:func:`~.simulation_stream.simulate_to_csv`, the memory check of :mod:`.memory`),
results (:class:`SimulationResult`, :mod:`.results_export`) and the progress line
(:class:`~.progress.Progress`).  This package imports the language
(:mod:`bondgraph`); the language never imports it (``docs/architecture.md``).
"""
from .evaluate import CompiledModel, compile_model
from .results import SimulationResult
from .simulation import simulate

__all__ = ["simulate", "compile_model", "CompiledModel", "SimulationResult"]
