"""plants: the plant library, the papers' block-diagram twins and the one model loader.

Just above :mod:`bondgraph` in the layer order of ``docs/architecture.md`` (imports it only).

:func:`load`
    A built-in name, a ``.json`` graph file, a ``.py`` file with ``build()``, or a graph
    (:mod:`plants.loading`); the command line and the diagnosis load models through it.
:func:`names`, :func:`describe`, :func:`build`
    The built-in models (:mod:`plants.library`: textbook graphs, the seed plants
    ``pam*`` and ``exoskeleton``, machines); ``plants/models.md`` documents how each
    was reconstructed from its paper.
:mod:`plants.blockdiagram`
    The papers' equation / block-diagram models, written independently of the bond
    graphs, to compare against (``bondcosim compare``).

>>> import plants
>>> plants.load("mass-spring-damper").equations().states
(p_m, q_k)
"""
from .library import build, describe, names
from .loading import load

__all__ = ["load", "names", "describe", "build"]
