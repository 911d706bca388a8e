"""bondcosim: the application (console script ``bondcosim`` and the demo).

The library lives in the layer packages ``bondgraph``, ``fmus``,
``estimators``, ``cosim`` and ``diagnosis``; this package only wires them to
the command line.
"""
__version__ = "0.1.0"
__all__ = ["__version__"]
