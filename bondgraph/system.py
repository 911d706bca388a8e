"""The result of a derivation: explicit state equations of a bond graph.

:class:`StateEquations` is an immutable value.  It is what every numeric part
of the project consumes (compiled evaluators, simulation, FMU export,
estimators), so its fields are the contract between the symbolic and the
numeric side:

.. math::

    \\dot x = f(t, x, u, z, d, p), \\qquad y = h(t, x, u, z, d, p),
    \\qquad 0 = r(t, x, u, z, d, p)

* ``x`` -- ``states``: momenta of I elements, displacements of C elements and
  whatever equation-defined elements declare, in integral causality only
  (storage in derivative causality has been eliminated).
* ``u`` -- ``inputs``: named source values (and inputs of modulated elements).
* ``p`` -- ``params``: named parameters with values in ``param_values``.
* ``z`` -- ``algebraic``: unknowns of nonlinear algebraic loops, defined
  implicitly by ``residuals`` (``0 = r``) and solved numerically at each
  evaluation.  Empty when every loop was solved symbolically.
* ``d`` -- ``held``: discrete variables of switched / sampled elements
  (e.g. Kikuuwe friction).  They are constant over a fixed integration
  sub-step and replaced by ``held_update`` (evaluated with the values at the
  start of the sub-step, which may use the step symbol ``step``) before it.
* ``t`` -- time, for sources given as functions of time.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Mapping

import sympy as sp
from .errors import ArgumentError

__all__ = ["StateEquations", "CausalityReport"]


@dataclass(frozen=True)
class CausalityReport:
    """What the causality assignment found besides plain integral causality.

    Attributes
    ----------
    derivative_storage : tuple of (element, bond)
        Storage elements in derivative causality (dependent storage), which the
        derivation eliminated.
    algebraic_loops : tuple of tuple of str
        Each loop as the bonds whose variables form it.
    loops_solved_symbolically : tuple of bool
        One flag per loop: linear loops are solved symbolically, the others
        numerically at each evaluation.
    arbitrary : tuple of str
        Elements or bonds whose causality was chosen arbitrarily (R elements
        in an algebraic loop, free bonds between two-ports).
    """

    derivative_storage: tuple = ()
    algebraic_loops: tuple = ()
    loops_solved_symbolically: tuple = ()
    arbitrary: tuple = ()

    def __str__(self) -> str:
        lines = []
        for elem, bond in self.derivative_storage:
            lines.append(f"derivative causality: {elem} on bond {bond} (dependent storage, eliminated)")
        for loop, sym in zip(self.algebraic_loops, self.loops_solved_symbolically):
            how = "solved symbolically" if sym else "solved numerically at each evaluation"
            lines.append(f"algebraic loop through bonds {', '.join(loop)} ({how})")
        return "\n".join(lines) if lines else "integral causality throughout, no algebraic loops"


def _frozen(mapping) -> Mapping:
    return MappingProxyType(dict(mapping or {}))


@dataclass(frozen=True, eq=False)
class StateEquations:
    """Explicit state equations of a bond graph (see the module docstring).

    Attributes
    ----------
    name : str
        Name of the graph the equations belong to.
    t : sympy.Symbol
        Time, s.
    states, inputs, params, algebraic, held : tuple of sympy.Symbol
        Ordered symbols (the order is the order of every numeric array).
    outputs : tuple of str
        Output names, in the order of ``h``.
    f : tuple of sympy.Expr
        Right-hand sides, one per state.
    h : tuple of sympy.Expr
        Output expressions, one per output.
    residuals : tuple of sympy.Expr
        ``0 = r`` defining ``algebraic``; same length.
    held_update : tuple of sympy.Expr
        New value of each held variable from the values at a sub-step start.
    step : sympy.Symbol
        Symbol of the integration sub-step used in ``held_update``, s.
    fixed_step : float or None
        Largest integration step the model honours, s; ``None`` for a smooth
        model that any ODE solver may integrate.
    param_values : mapping str -> float
        Default parameter values (SI).
    initial_state, input_defaults, held_initial : mapping str -> float
        Defaults: initial state, nominal inputs (also the default operating
        point), initial held values.
    units : mapping str -> str
        Unit of every state, input, parameter, output and held variable.
    descriptions : mapping str -> str
        One-line description of the same names (may be empty strings).
    owners : mapping str -> tuple (element, variable)
        Which element (and which of its variables) each symbol belongs to.
    input_functions : mapping str -> sympy.Expr
        Inputs that are given functions of time (``t``); these are still in
        ``inputs`` so a user may override them.
    input_delays : mapping str -> InputDelay
        Inputs that are another input late (:class:`~bondgraph.elements.base.InputDelay`):
        still in ``inputs``; simulators fill them from their source's values
        (:mod:`bondgraph.numerics.input_delays`).
    report : CausalityReport
        Derivative causality and algebraic loops found.
    assignments : tuple of (sympy.Symbol, sympy.Expr)
        Ordered causal assignments: named intermediates (element locals such
        as ``valve1.alpha``, bond variables such as ``f_m1``), each an
        expression of states, inputs, parameters, held and algebraic
        variables and the earlier intermediates (see
        :mod:`bondgraph.assignments`).  Empty for equations built by hand.
    f_short, h_short, held_update_short : tuple of sympy.Expr
        ``f``, ``h`` and ``held_update`` in terms of the assignments:
        substituting ``assignments`` in reverse order gives the flat forms.
        Empty tuples mean "same as the flat form".
    guards : tuple of DerivedGuard
        Physical-domain conditions (:mod:`bondgraph.guards`), expressions in
        ``t``, states, inputs, params and held symbols.
    param_bounds : mapping str -> (float or None, float or None)
        Physical range ``(min, max)`` of each bounded parameter (inclusive).
    """

    name: str
    t: sp.Symbol
    states: tuple
    inputs: tuple
    params: tuple
    outputs: tuple
    f: tuple
    h: tuple
    algebraic: tuple = ()
    residuals: tuple = ()
    held: tuple = ()
    held_update: tuple = ()
    step: sp.Symbol = field(default_factory=lambda: sp.Symbol("h_step", real=True))
    fixed_step: float | None = None
    param_values: Mapping = field(default_factory=dict)
    initial_state: Mapping = field(default_factory=dict)
    input_defaults: Mapping = field(default_factory=dict)
    held_initial: Mapping = field(default_factory=dict)
    units: Mapping = field(default_factory=dict)
    descriptions: Mapping = field(default_factory=dict)
    owners: Mapping = field(default_factory=dict)
    input_functions: Mapping = field(default_factory=dict)
    input_delays: Mapping = field(default_factory=dict)
    report: CausalityReport = field(default_factory=CausalityReport)
    assignments: tuple = ()
    f_short: tuple = ()
    h_short: tuple = ()
    held_update_short: tuple = ()
    guards: tuple = ()
    param_bounds: Mapping = field(default_factory=dict)

    def __post_init__(self):
        for name in ("states", "inputs", "params", "outputs", "f", "h",
                     "algebraic", "residuals", "held", "held_update", "guards"):
            object.__setattr__(self, name, tuple(getattr(self, name)))
        object.__setattr__(self, "assignments", tuple((s, e) for s, e in self.assignments))
        for name, flat in (("f_short", "f"), ("h_short", "h"), ("held_update_short", "held_update")):
            value = tuple(getattr(self, name)) or getattr(self, flat)
            if len(value) != len(getattr(self, flat)):
                raise ArgumentError(f"{len(value)} {name} expressions for {len(getattr(self, flat))} {flat}")
            object.__setattr__(self, name, value)
        for name in ("param_values", "initial_state", "input_defaults", "held_initial",
                     "units", "descriptions", "owners", "input_functions", "input_delays", "param_bounds"):
            object.__setattr__(self, name, _frozen(getattr(self, name)))
        if len(self.f) != len(self.states):
            raise ArgumentError(f"{len(self.f)} right-hand sides for {len(self.states)} states")
        if len(self.h) != len(self.outputs):
            raise ArgumentError(f"{len(self.h)} output expressions for {len(self.outputs)} outputs")
        if len(self.residuals) != len(self.algebraic):
            raise ArgumentError(f"{len(self.residuals)} residuals for {len(self.algebraic)} algebraic unknowns")
        if len(self.held_update) != len(self.held):
            raise ArgumentError(f"{len(self.held_update)} updates for {len(self.held)} held variables")

    # -- names -------------------------------------------------------------
    @property
    def state_names(self) -> tuple[str, ...]:
        return tuple(s.name for s in self.states)

    @property
    def input_names(self) -> tuple[str, ...]:
        return tuple(s.name for s in self.inputs)

    @property
    def param_names(self) -> tuple[str, ...]:
        return tuple(s.name for s in self.params)

    @property
    def held_names(self) -> tuple[str, ...]:
        return tuple(s.name for s in self.held)

    @property
    def n_states(self) -> int:
        return len(self.states)

    @property
    def is_smooth(self) -> bool:
        """True when an adaptive ODE solver may integrate the model."""
        return self.fixed_step is None and not self.held

    # -- presentation and analysis -----------------------------------------
    def pretty(self, *, simplify: bool = False, flat: bool = False) -> str:
        """The equations as readable text (see :func:`bondgraph.printing.pretty`)."""
        from .printing import pretty
        return pretty(self, simplify=simplify, flat=flat)

    def latex(self, *, flat: bool = False) -> str:
        """The equations as a LaTeX ``aligned`` block (assignments first unless `flat`)."""
        from .printing import latex
        return latex(self, flat=flat)

    def assignment_names(self) -> tuple[str, ...]:
        """Names of the ordered intermediates, e.g. ``("valve1.alpha", ...)``."""
        return tuple(s.name for s, _ in self.assignments)

    def to_dict(self) -> dict:
        """JSON-ready summary (names, parameter values, expressions as strings)."""
        from .printing import equations_to_dict
        return equations_to_dict(self)

    def linearize(self, operating_point=None, **kwargs):
        """Linearise at `operating_point` (see :func:`bondgraph.linearization.linearize`)."""
        from .linearization import linearize
        return linearize(self, operating_point, **kwargs)

    def __str__(self) -> str:
        return self.pretty()

    def _repr_latex_(self) -> str:
        return "$" + self.latex() + "$"
