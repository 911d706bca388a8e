"""cosim: the co-simulation master for FMUs and Python components.

The co-simulation engine only; the papers' closed loops built on it are in
:mod:`reproductions` (``docs/architecture.md``).

Components
    :class:`Component` (the protocol the master drives), :class:`Port`,
    :class:`PythonBlock` (base class for Python components),
    :class:`FMUComponent` (any FMI 2.0 / 3.0 Co-Simulation FMU, stepped
    through fmpy's raw C functions).
Blocks
    :class:`Constant`, :class:`Step`, :class:`Function`, :class:`Table`,
    :class:`PI` (discrete, with limits and anti-windup), :class:`Antagonistic`
    (one command split into an antagonistic pair).
Master
    :class:`CoSimulation` (fixed communication step, execution order and
    algebraic-loop detection from direct feedthrough) returning a
    :class:`CosimResult` (signals ``"component.port"`` with units; CSV, plot).

>>> from cosim import CoSimulation, FMUComponent, PI, Step
>>> plant = FMUComponent("msd.fmu")                                     # doctest: +SKIP
>>> pi = PI("pi", kp=200.0, ki=400.0, unit_in="m", unit_out="N")
>>> sim = CoSimulation([plant, pi, Step("r", 0.1, after=0.05, unit="m")],
...                    [("r.y", "pi.r"), ("msd.x", "pi.y_m"), ("pi.u", "msd.F")],
...                    step=1e-3)                                       # doctest: +SKIP
>>> result = sim.run(2.0)                                               # doctest: +SKIP
>>> result.to_csv("closed_loop.csv"); fig = result.plot()               # doctest: +SKIP
"""
from .blocks import PI, Antagonistic, Constant, Function, Step, Table
from .component import Component, Port, PythonBlock
from .fmu_component import FMUComponent
from .master import CoSimulation, CosimResult

__all__ = [
    "Component", "Port", "PythonBlock", "FMUComponent",
    "Constant", "Step", "Function", "Table", "PI", "Antagonistic",
    "CoSimulation", "CosimResult",
]
