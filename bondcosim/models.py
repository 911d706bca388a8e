"""Resolve a MODEL argument: a built-in name, a JSON graph file, or a .py file with ``build()``."""
from __future__ import annotations

import importlib.util
from pathlib import Path

from bondgraph.errors import GraphError, MissingFileError
from bondgraph.graph import BondGraph

__all__ = ["load_model"]


def load_model(spec: str) -> BondGraph:
    """The bond graph named by `spec`.

    Parameters
    ----------
    spec : str
        A built-in model name (``bondcosim list``), a path to a ``.json``
        graph file, or a path to a ``.py`` file defining ``build()`` that
        returns a :class:`~bondgraph.graph.BondGraph`.
    """
    from bondgraph import library

    path = Path(spec)
    if path.suffix == ".json":
        if not path.is_file():
            raise MissingFileError(f"model file {spec!r} does not exist", path=spec)
        from bondgraph.io_json import load
        return load(path)
    if path.suffix == ".py":
        if not path.is_file():
            raise MissingFileError(f"model file {spec!r} does not exist", path=spec)
        module_spec = importlib.util.spec_from_file_location(f"bondcosim_user_model_{path.stem}", path)
        module = importlib.util.module_from_spec(module_spec)
        try:
            module_spec.loader.exec_module(module)
        except Exception as exc:  # a user file: report what went wrong in it, in one line
            raise GraphError(f"model file {spec!r} failed to import: {exc.__class__.__name__}: {exc}") from None
        build = getattr(module, "build", None)
        if not callable(build):
            raise GraphError(f"model file {spec!r} defines no build() function")
        graph = build()
        if not isinstance(graph, BondGraph):
            raise GraphError(f"build() in {spec!r} returned {type(graph).__name__}, not a BondGraph")
        return graph
    if spec in library.names():
        return library.build(spec)
    raise GraphError(f"unknown model {spec!r}: not a built-in model ({', '.join(library.names())}), "
                     "nor a .json or .py file")
