"""The variables of an exported FMU: names, value references, causality, units.

:func:`variable_layout` turns :class:`~bondgraph.system.StateEquations` into
the list of :class:`FmuVariable` that both the model description
(:mod:`fmus.model_description`) and the generated C header
(:mod:`fmus.c_header`) are written from, so the two cannot disagree.

Value references are positions in the C array ``v[]`` (see
``fmus/c/bc_fmu_core.h``)::

    states x | der(x) | inputs u | parameters p | held d | outputs y | solver_step | max_substeps | solver | tolerance

FMI 3.0 adds ``time`` (causality ``independent``) after them.  An output that
is one of the states under the same name (e.g. every output of ``chain``) is
not a separate variable: the state itself gets causality ``output``.
"""
from __future__ import annotations

import dataclasses
import math
import re
from dataclasses import dataclass

import sympy as sp

from fmus.errors import FMUError

__all__ = ["FmuVariable", "variable_layout", "derivative_unit", "model_identifier", "SOLVER_STEP",
           "MAX_SUBSTEPS", "DEFAULT_MAX_SUBSTEPS", "SOLVER", "TOLERANCE"]

#: Name of the parameter holding the internal fixed solver step of Co-Simulation.
SOLVER_STEP = "solver_step"
#: Name of the parameter bounding the internal sub-steps of one doStep.
MAX_SUBSTEPS = "max_substeps"
#: Names of the parameters choosing the Co-Simulation solver and its relative tolerance.
SOLVER, TOLERANCE = "solver", "tolerance"
#: Its default: 1e6 sub-steps (about 0.05 s of CPU for a 2-state model, 1-2 s for ``pam``);
#: a longer doStep returns Discard instead of blocking.
DEFAULT_MAX_SUBSTEPS = 1e6


@dataclass(frozen=True)
class FmuVariable:
    """One scalar Real (FMI 2.0) / Float64 (FMI 3.0) variable.

    Attributes
    ----------
    name : str
    vr : int
        Value reference (= index into the C array ``v[]``).
    kind : str
        ``"state"``, ``"derivative"``, ``"input"``, ``"parameter"``, ``"held"``,
        ``"output"``, ``"solver_step"``, ``"max_substeps"``, ``"solver"``, ``"tolerance"``,
        ``"time"`` or ``"indicator"`` (FMI 3.0 event indicator).
    causality, variability : str
        FMI attributes.
    initial : str or None
        ``"exact"`` or ``"calculated"``; None where FMI wants none (inputs).
    start : float or None
        Start value (None for calculated variables).
    unit, description : str
    state_vr : int or None
        For a derivative, the value reference of its state.
    dependencies : tuple of int or None
        For an output or a derivative, value references of the states and inputs
        it depends on.
    min, max : float or None
        Physical range (parameter bounds, single-variable guards), in `unit`.
    nominal : float or None
        Magnitude of the variable (states, parameters), in `unit`.
    """

    name: str
    vr: int
    kind: str
    causality: str
    variability: str
    initial: str | None
    start: float | None
    unit: str = ""
    description: str = ""
    state_vr: int | None = None
    dependencies: tuple | None = None
    min: float | None = None
    max: float | None = None
    nominal: float | None = None


def derivative_unit(unit: str) -> str:
    """Unit of the time derivative of a quantity in `unit`, in a form
    :func:`bondgraph.units.parse_unit` reads (one ``/``): ``"N s"`` -> ``"N"``,
    ``"m"`` -> ``"m/s"``, ``"mm/s"`` -> ``"mm/(s s)"``, ``"J/(kg K)"`` -> ``"J/(kg K s)"``."""
    unit = unit.strip()
    if not unit or unit == "1":
        return "1/s"
    if unit == "s":
        return "1"
    if unit.endswith(" s") and "/" not in unit:
        return unit[:-2].strip()
    num, slash, den = unit.partition("/")
    if not slash:
        return f"{unit}/s"
    den = den.strip()
    if den.startswith("(") and den.endswith(")"):
        den = den[1:-1].strip()
    return f"{num.strip()}/({den} s)"


def _output_dependencies(eqs, expr) -> set:
    """States and inputs `expr` depends on, through the algebraic loops too."""
    syms = set(sp.sympify(expr).free_symbols)
    if syms & set(eqs.algebraic):
        for r in eqs.residuals:
            syms |= sp.sympify(r).free_symbols
    return syms & (set(eqs.states) | set(eqs.inputs))


_KIND_WORDS = {"state": "state", "input": "input", "parameter": "parameter", "held": "held variable",
               "output": "output"}


def _completed(eqs, v: FmuVariable) -> FmuVariable:
    """Every variable with a unit (``"1"`` when dimensionless), a description and,
    for states, inputs and parameters, a nominal value (magnitude of its start value or
    of the model's operating point; none when that is 0, so FMI's default 1 applies)."""
    unit = v.unit or "1"
    desc = v.description or f"{_KIND_WORDS.get(v.kind, v.kind)} {v.name} of {eqs.name}"
    nominal = None
    if v.kind in ("state", "input", "parameter"):
        scale = abs(v.start or 0.0) or abs(float(eqs.initial_state.get(v.name, 0.0)))
        nominal = scale if scale > 0.0 and math.isfinite(scale) else None
    return dataclasses.replace(v, unit=unit, description=desc, nominal=nominal)


def _with_ranges(eqs, variables) -> list[FmuVariable]:
    """Parameter bounds and single-variable guards (``P_1 >= 0``) as min/max."""
    ranges = {name: lo_hi for name, lo_hi in eqs.param_bounds.items()}
    for g in eqs.guards:
        if isinstance(g.expr, sp.Symbol):
            lo, hi = ranges.get(g.expr.name, (None, None))
            lo = g.guard.min if lo is None else (lo if g.guard.min is None else max(lo, g.guard.min))
            hi = g.guard.max if hi is None else (hi if g.guard.max is None else min(hi, g.guard.max))
            ranges[g.expr.name] = (lo, hi)
    out = []
    for v in variables:
        if v.name in ranges and v.kind in ("state", "input", "parameter", "held", "output"):
            lo, hi = ranges[v.name]
            v = dataclasses.replace(v, min=lo if lo is not None else v.min,
                                    max=hi if hi is not None else v.max)
        out.append(v)
    return out


def variable_layout(eqs, solver_step: float, *, fmi_version: int = 2,
                    max_substeps: float = DEFAULT_MAX_SUBSTEPS,
                    tolerance: float = 1e-8, solver: int = 0,
                    indicators: tuple = ()) -> list[FmuVariable]:
    """Every variable of the FMU of `eqs`, in value-reference order.

    Parameters
    ----------
    eqs : StateEquations
        With no inputs given as functions of time (see :func:`fmus.exporter.export`).
    solver_step : float
        Start value of the ``solver_step`` parameter, s.
    max_substeps : float
        Start value of the ``max_substeps`` parameter (dimensionless).
    tolerance : float
        Start value of the ``tolerance`` parameter (variable-step solver).
    solver : {0, 1}
        Start value of the ``solver`` parameter (0 fixed-step RK4, 1 Dormand-Prince).
    indicators : sequence of str
        The surface of each event indicator (text for its description); FMI 3.0
        declares a variable ``event_indicator_<k>`` for each, after ``time``.
    fmi_version : {2, 3}
        3 appends the ``time`` variable (and the event indicators).

    Returns
    -------
    list of FmuVariable

    Raises
    ------
    FMUError
        Two variables share a name (an output named like a state but computed
        differently, or a parameter called ``solver_step``).
    """
    units, desc = eqs.units, eqs.descriptions
    nx, nu, np_, nd = len(eqs.states), len(eqs.inputs), len(eqs.params), len(eqs.held)
    vr_u = 2 * nx
    vr_p = vr_u + nu
    vr_d = vr_p + np_
    vr_y = vr_d + nd
    state_vr = {s.name: i for i, s in enumerate(eqs.states)}
    dep_vr = {**{eqs.states[i]: i for i in range(nx)},
              **{s: vr_u + i for i, s in enumerate(eqs.inputs)}}

    merged = {}   # output index -> state name, for outputs that are just the state
    for i, (name, expr) in enumerate(zip(eqs.outputs, eqs.h)):
        if name in state_vr and sp.sympify(expr) == eqs.states[state_vr[name]]:
            merged[i] = name
    as_output = set(merged.values())

    out: list[FmuVariable] = []
    for i, s in enumerate(eqs.states):
        is_out = s.name in as_output
        out.append(FmuVariable(
            s.name, i, "state", "output" if is_out else "local", "continuous", "exact",
            float(eqs.initial_state.get(s.name, 0.0)), units.get(s.name, ""),
            desc.get(s.name, "") or "state", dependencies=(i,) if is_out else None))
    for i, s in enumerate(eqs.states):
        deps = tuple(sorted(dep_vr[x] for x in _output_dependencies(eqs, eqs.f[i])))
        out.append(FmuVariable(
            f"der({s.name})", nx + i, "derivative", "local", "continuous", "calculated", None,
            derivative_unit(units.get(s.name, "")), f"time derivative of {s.name}", state_vr=i,
            dependencies=deps))
    for i, s in enumerate(eqs.inputs):
        out.append(FmuVariable(
            s.name, vr_u + i, "input", "input", "continuous", None,
            float(eqs.input_defaults.get(s.name, 0.0)), units.get(s.name, ""), desc.get(s.name, "")))
    for i, s in enumerate(eqs.params):
        out.append(FmuVariable(
            s.name, vr_p + i, "parameter", "parameter", "fixed", "exact",
            float(eqs.param_values[s.name]), units.get(s.name, ""), desc.get(s.name, "")))
    for i, s in enumerate(eqs.held):
        out.append(FmuVariable(
            s.name, vr_d + i, "held", "local", "discrete", "exact",
            float(eqs.held_initial.get(s.name, 0.0)), units.get(s.name, ""),
            desc.get(s.name, "") or "held over each solver sub-step"))
    for i, (name, expr) in enumerate(zip(eqs.outputs, eqs.h)):
        if i in merged:
            continue
        deps = tuple(sorted(dep_vr[s] for s in _output_dependencies(eqs, expr)))
        out.append(FmuVariable(
            name, vr_y + i, "output", "output", "continuous", "calculated", None,
            units.get(name, ""), desc.get(name, ""), dependencies=deps))
    out.append(FmuVariable(
        SOLVER_STEP, vr_y + len(eqs.outputs), "solver_step", "parameter", "fixed", "exact",
        float(solver_step), "s", "largest internal RK4 sub-step of Co-Simulation doStep",
        min=0.0))
    out.append(FmuVariable(
        MAX_SUBSTEPS, vr_y + len(eqs.outputs) + 1, "max_substeps", "parameter", "fixed", "exact",
        float(max_substeps), "1", "most internal sub-steps one doStep may take; a longer step "
        "returns Discard (never a silent hang)", min=1.0))
    smooth = not eqs.held
    out.append(FmuVariable(
        SOLVER, vr_y + len(eqs.outputs) + 2, "solver", "parameter", "fixed", "exact", float(solver), "1",
        "Co-Simulation solver: 0 fixed-step RK4 (solver_step), 1 variable-step Dormand-Prince 5(4)"
        + ("" if smooth else " (not offered: held variables need the fixed step)"),
        min=0.0, max=1.0 if smooth else 0.0))
    out.append(FmuVariable(
        TOLERANCE, vr_y + len(eqs.outputs) + 3, "tolerance", "parameter", "fixed", "exact",
        float(tolerance), "1", "relative tolerance of the variable-step solver (absolute: "
        "tolerance times each state's nominal)", min=0.0))
    out = _with_ranges(eqs, out)
    out = [_completed(eqs, v) for v in out]
    if fmi_version == 3:
        out.append(FmuVariable("time", out[-1].vr + 1, "time", "independent", "continuous",
                               None, None, "s", "simulation time"))
        for k, text in enumerate(indicators, start=1):   # FMI 3.0 names its event indicators
            out.append(FmuVariable(f"event_indicator_{k}", out[-1].vr + 1, "indicator", "local",
                                   "continuous", "calculated", None, "1",
                                   f"event indicator: {text}"))

    seen: dict[str, FmuVariable] = {}
    for v in out:
        if v.name in seen:
            raise FMUError(f"model {eqs.name!r}: the {seen[v.name].kind} and the {v.kind} are both "
                           f"named {v.name!r}; rename one before exporting")
        seen[v.name] = v
    return out


def model_identifier(name: str) -> str:
    """A C identifier and file name from a model name (``"pam-locked"`` -> ``"pam_locked"``)."""
    ident = re.sub(r"\W", "_", name)
    return ident if ident and not ident[0].isdigit() else f"m_{ident}"
