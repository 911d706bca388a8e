"""bondcosim: the application (console script ``bondcosim`` and the demo).

The library lives in the layer packages ``bondgraph`` (with ``bondgraph.numerics``),
``plants``, ``fmus``, ``estimators``, ``cosim``, ``reproductions``, ``diagnosis`` and
``sweeps`` (``docs/architecture.md``); this package only wires them to the command line.
"""
__version__ = "0.1.0"
__all__ = ["__version__"]
