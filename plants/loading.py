"""The one model loader: a built-in name, a JSON graph file, a ``.py`` file with ``build()``, or a graph."""
from __future__ import annotations

import importlib.util
import os
from pathlib import Path

from bondgraph.graph import BondGraph

from . import library
from .errors import ArgumentTypeError, MissingFileError, ModelFileError, UnknownModelError

__all__ = ["load"]


def load(model) -> BondGraph:
    """The bond graph `model` names.

    Parameters
    ----------
    model : str, os.PathLike or BondGraph
        A built-in model name (:func:`plants.names`, ``bondcosim list``), a path to a
        ``.json`` graph file (``docs/json-schema.md``), a path to a ``.py`` file
        defining ``build()`` that returns a :class:`~bondgraph.graph.BondGraph`, or a
        graph (returned as it is).

    Returns
    -------
    BondGraph
        A fresh graph for a name or a file.

    Raises
    ------
    UnknownModelError
        Neither a built-in name nor a ``.json``/``.py`` path (the message lists the names).
    MissingFileError
        A ``.json`` or ``.py`` path that does not exist.
    ModelFileError
        A ``.py`` file that fails to import or whose ``build()`` is missing or returns no graph.
    SchemaError
        A malformed JSON graph (every problem listed).
    ArgumentTypeError
        `model` is of another type.

    >>> load("rlc").equations().states
    (p_L, q_Cs)
    """
    if isinstance(model, BondGraph):
        return model
    if not isinstance(model, (str, os.PathLike)):
        raise ArgumentTypeError(f"model must be a BondGraph, a built-in model name or a .json/.py file; "
                                f"found {type(model).__name__}", name="model")
    spec, path = os.fspath(model), Path(model)
    if path.suffix in (".json", ".py") and not path.is_file():
        raise MissingFileError(f"model file {spec!r} does not exist", path=spec)
    if path.suffix == ".json":
        from bondgraph.io_json import load as load_json
        return load_json(path)
    if path.suffix == ".py":
        return _from_python_file(path, spec)
    if spec in library.names():
        return library.build(spec)
    raise UnknownModelError(spec, library.names())


def _from_python_file(path: Path, spec: str) -> BondGraph:
    module_spec = importlib.util.spec_from_file_location(f"bondcosim_user_model_{path.stem}", path)
    module = importlib.util.module_from_spec(module_spec)
    try:
        module_spec.loader.exec_module(module)
    except Exception as exc:  # a user file: report what went wrong in it, in one line
        raise ModelFileError(f"model file {spec!r} failed to import: {exc.__class__.__name__}: {exc}",
                             path=spec) from None
    build = getattr(module, "build", None)
    if not callable(build):
        raise ModelFileError(f"model file {spec!r} defines no build() function", path=spec)
    graph = build()
    if not isinstance(graph, BondGraph):
        raise ModelFileError(f"build() in {spec!r} returned {type(graph).__name__}, not a BondGraph", path=spec)
    return graph
