"""bondgraph.numerics: the state equations of :mod:`bondgraph` turned into numbers.

Code generation (:mod:`.codegen_c`, :mod:`.codegen_c_templates`, :mod:`.c_build`),
compiled and numpy evaluation (:func:`compile_model`, :mod:`.evaluate_c`,
:mod:`.evaluate_numpy`, :mod:`.evaluate_samples`), simulation (:func:`simulate`,
:func:`~.simulation_stream.simulate_to_csv`, the memory check of :mod:`.memory`),
results (:class:`SimulationResult`, :mod:`.results_export`) and the progress line
(:class:`~.progress.Progress`).  This package imports the language
(:mod:`bondgraph`); the language never imports it (``docs/architecture.md``).
"""
__all__ = ["simulate", "compile_model", "CompiledModel", "SimulationResult"]

_LAZY = {  # imported on first use: `import bondgraph.numerics.progress` stays cheap (fast CLI start)
    "simulate": "simulation",
    "compile_model": "evaluate",
    "CompiledModel": "evaluate",
    "SimulationResult": "results",
}


def __getattr__(name):
    if name not in _LAZY:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    import importlib
    value = getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
    globals()[name] = value
    return value
