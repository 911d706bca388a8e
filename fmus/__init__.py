"""fmus: bond graph -> FMU (generated C, compiled) and FMU loading helpers.

Above ``plants`` in the layer order of ``docs/architecture.md`` (imports ``bondgraph``, ``plants``).

>>> import plants.library as library
>>> from fmus import export
>>> path = export(library.build("mass-spring-damper"), tmp / "msd.fmu")   # doctest: +SKIP

:func:`export` writes a binary FMU (FMI 2.0 or 3.0) offering Co-Simulation,
and Model Exchange for smooth models.  It lives in :mod:`fmus.exporter`: a submodule
named like the function would share the package attribute ``fmus.export`` with it.
"""
from .exporter import default_solver_step, export

__all__ = ["export", "default_solver_step"]
