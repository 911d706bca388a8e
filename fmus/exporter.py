"""Export a bond graph as a binary FMU (FMI 2.0 or 3.0; Model Exchange and Co-Simulation).

The FMU's C is generated in three parts:

* ``model_kernels.c`` -- the row kernels of :mod:`bondgraph.numerics.codegen_c`
  (f, h, held-variable updates, the Newton solver of algebraic loops and the
  RK4 driver ``bc_rk4``), the same code :func:`bondgraph.numerics.simulate` runs;
* ``model.h`` -- sizes, value references, start values (:mod:`fmus.c_header`);
* one fixed wrapper per FMI version in ``fmus/c/`` on top of the
  version-independent ``bc_fmu_core.h``,

compiled by the system C compiler with hidden visibility, so the shared
library exports only the ``fmi2*`` / ``fmi3*`` functions.  The FMU ships the
same files under ``sources/`` (:mod:`fmus.sources`) so that it can be rebuilt
from them alone.

Co-Simulation integrates with classic RK4 in equal sub-steps no longer than
the ``solver_step`` parameter, inputs held over the communication step and
held variables updated at each sub-step start -- exactly
:func:`bondgraph.numerics.simulate`'s fixed-step scheme (``solver = 0``), or with the
embedded Dormand-Prince 5(4) (``solver = 1``).  Model Exchange is offered only
for smooth models (no held variables, no ``fixed_step``): a model that needs a
fixed step cannot honour an external integrator's steps.  It has an event
indicator per switching surface of the laws (:func:`event_indicators`), and
both interfaces give directional derivatives from the symbolic partials
(``fmus/c/bc_partials.h``).
"""
from __future__ import annotations

import dataclasses
import hashlib
import math
import platform
import re
import sys
import uuid
import zipfile
from pathlib import Path

import numpy as np
import sympy as sp

from bondgraph.numerics.codegen_c import generate_source, guard_source, indicator_source, partials_source
from bondgraph.derivatives import switching_surfaces
from bondgraph.guards import check_param_bounds
from fmus.errors import (BondcosimError, CompilationError, DerivationError, FMUError, FMUModelTypeError,
                         ParameterError)

from .build import compile_fmu_binary
from .c_header import model_header
from .layout import DEFAULT_MAX_SUBSTEPS, model_identifier, variable_layout
from .sources import compiled_sources, source_files
from .model_description import model_description_xml

__all__ = ["export", "default_solver_step", "default_experiment", "fmu_equations", "binary_platform",
           "event_indicators", "SOLVERS", "STIFF_STEP"]

#: Co-Simulation solvers an FMU can start with: name -> value of its ``solver`` parameter.
SOLVERS = {"rk4": 0, "dopri": 1}
#: Below this RK4 step (s, by the accuracy rule) a model counts as stiff: its step follows stability.
STIFF_STEP = 1e-5

#: Fixed date stamped into exported files, so the same model gives the same bytes.
_EPOCH = (1980, 1, 1, 0, 0, 0)


def binary_platform(fmi_version: int) -> str:
    """The ``binaries/`` folder of this machine (``linux64`` / ``x86_64-linux``).

    Raises
    ------
    FMUError
        On a platform the exporter does not build for.
    """
    machine = platform.machine().lower()
    if sys.platform.startswith("linux") and machine in ("x86_64", "amd64"):
        return "linux64" if fmi_version == 2 else "x86_64-linux"
    raise FMUError(f"FMU export builds Linux x86-64 binaries only; this machine is "
                   f"{sys.platform}/{machine}")


def fmu_equations(eqs):
    """`eqs` with every input given as a function of time substituted into the
    expressions (an FMU input has a start value, not a time function).

    Returns
    -------
    StateEquations
    """
    if not eqs.input_functions:
        return eqs
    sub = {s: sp.sympify(eqs.input_functions[s.name]) for s in eqs.inputs if s.name in eqs.input_functions}

    def rep(exprs):
        return tuple(sp.sympify(e).xreplace(sub) for e in exprs)

    return dataclasses.replace(
        eqs, inputs=tuple(s for s in eqs.inputs if s not in sub),
        f=rep(eqs.f), h=rep(eqs.h), residuals=rep(eqs.residuals),
        held_update=rep(eqs.held_update), input_functions={},
        assignments=tuple((a, sp.sympify(e).xreplace(sub)) for a, e in eqs.assignments),
        f_short=rep(eqs.f_short), h_short=rep(eqs.h_short), held_update_short=rep(eqs.held_update_short),
        guards=tuple(dataclasses.replace(g, expr=sp.sympify(g.expr).xreplace(sub)) for g in eqs.guards))


def default_solver_step(eqs) -> float:
    """Internal Co-Simulation step, s: the model's ``fixed_step`` if it has one,
    else ``0.05 / rho(A)`` (A the Jacobian at the default operating point, so RK4's
    relative error per unit time stays near 1e-7) rounded down to 1-2-5 and at
    most 1 ms; 1e-4 s if the model cannot be linearised there.

    A stiff model, one whose rule above gives less than :data:`STIFF_STEP`,
    gets ``1 / rho(A)`` instead: its fastest modes are well damped (the
    exoskeleton's motor electrics and compliant transmission, |lambda| up to
    5e4 1/s), so RK4 needs the step for stability (|lambda| h < 2.78), not
    accuracy; on the exoskeleton 1e-5 s gives the 5e-7 s step's answer to
    2e-10 at a sixteenth of the cost (``benchmarks/fmu_solvers.py``)."""
    if eqs.fixed_step:
        return float(eqs.fixed_step)
    try:
        a = np.asarray(eqs.linearize().A, dtype=float)
        rho = float(np.max(np.abs(np.linalg.eigvals(a)))) if a.size else 0.0
    except (BondcosimError, np.linalg.LinAlgError, ValueError, TypeError, ArithmeticError):
        return 1e-4   # no linearisation at the default point: a safe small step
    if not math.isfinite(rho) or rho <= 0.0:
        return 1e-3
    h = 0.05 / rho
    if h < STIFF_STEP:
        h = 1.0 / rho
    decade = 10.0 ** math.floor(math.log10(h))
    mantissa = max(m for m in (1.0, 2.0, 5.0) if m * decade <= h * (1 + 1e-12))
    return min(1e-3, mantissa * decade)


def _round_125(x: float, *, up: bool) -> float:
    """`x` rounded to 1, 2 or 5 times a power of ten (up or down)."""
    decade = 10.0 ** math.floor(math.log10(x))
    steps = [m * decade for m in (1.0, 2.0, 5.0, 10.0)]
    return min(v for v in steps if v >= x * (1 - 1e-12)) if up else \
        max(v for v in steps if v <= x * (1 + 1e-12))


def default_experiment(eqs, solver_step: float) -> dict:
    """``DefaultExperiment`` of the FMU of `eqs`: start 0, stop and communication step, s.

    ``stopTime`` is five times the slowest time constant of the linearisation
    at the default operating point (:math:`5 / \\min |\\mathrm{Re}\\,\\lambda|`
    over the stable non-zero eigenvalues) rounded up to 1-2-5 and kept in
    [1 ms, 100 s]; 1 s when there is none.  ``stepSize`` is stopTime/1000
    rounded up to 1-2-5, at most 1 ms for a model with a ``fixed_step`` (the
    sample of its scheme), never below `solver_step`.
    """
    stop = 1.0
    try:
        lam = np.linalg.eigvals(np.asarray(eqs.linearize().A, dtype=float)) if eqs.states else []
        rates = [-r for r in np.real(lam) if r < -1e-12 and math.isfinite(r)]
        if rates:
            stop = min(100.0, max(1e-3, _round_125(5.0 / min(rates), up=True)))
    except (BondcosimError, np.linalg.LinAlgError, ValueError, TypeError, ArithmeticError):
        pass   # no linearisation at the default point: the 1 s default
    step = _round_125(stop / 1000.0, up=True)
    if eqs.fixed_step:
        step = min(step, 1e-3)
    step = max(step, solver_step)
    return {"startTime": 0.0, "stopTime": stop, "stepSize": step}


def event_indicators(eqs) -> list[tuple]:
    """Model Exchange event indicators of `eqs`: every switching surface of its laws
    (:func:`bondgraph.derivatives.switching_surfaces` of the assignments, f, h and the
    loop residuals) as ``(g, switch)``; none for a model that offers Co-Simulation only."""
    if not eqs.is_smooth:
        return []
    varying = {eqs.t, *eqs.states, *eqs.inputs, *eqs.algebraic, *(a for a, _ in eqs.assignments)}
    return switching_surfaces([*(e for _, e in eqs.assignments), *eqs.f_short, *eqs.h_short,
                               *eqs.residuals], varying)


def _partials(eqs) -> str:
    """C of the symbolic partials (directional derivatives), or "" when a law has none."""
    try:
        return partials_source(eqs)
    except (CompilationError, DerivationError):
        return ""


def _switch_text(g, switch) -> str:
    """``"P_1 - P_out = 0 (a switch of sign)"``, at most 160 characters."""
    text = str(g)
    text = text if len(text) <= 120 else text[:117] + "..."
    return f"{text} = 0 (a switch of {type(switch).__name__})"


def _equations_of(model):
    if hasattr(model, "equations") and callable(model.equations):
        # FMI has no delay primitive: a delayed input becomes Pade states (bondgraph.editing_delays)
        realised = getattr(model, "with_delays_realised", None)
        return (realised() if realised is not None else model).equations()
    if hasattr(model, "states") and hasattr(model, "f"):
        if model.input_delays:
            raise FMUModelTypeError(f"model {model.name!r} has delayed inputs ({', '.join(model.input_delays)}), "
                                    "which an FMU cannot hold: export the bond graph (its delays become "
                                    "Pade states, BondGraph.with_delays_realised)")
        return model
    raise FMUModelTypeError(f"export needs a BondGraph or StateEquations, got {type(model).__name__}")


def export(model, path, *, fmi_version: int = 2, solver: str = "rk4",
           solver_step: float | None = None, tolerance: float = 1e-8,
           max_substeps: float = DEFAULT_MAX_SUBSTEPS,
           params=None, identifier: str | None = None, description: str | None = None,
           stop_time: float | None = None, step_size: float | None = None,
           author: str = "bondcosim", version: str = "1.0", license: str = "MIT",
           copyright: str = ""):
    """Write `model` as a binary FMU.

    Parameters
    ----------
    model : BondGraph or StateEquations
    path : str or path-like
        Output ``.fmu`` file (parent directories are created).
    fmi_version : {2, 3}
    solver : {"rk4", "dopri"}
        Start value of the ``solver`` parameter: Co-Simulation integrates with
        fixed-step RK4 (0) or variable-step Dormand-Prince 5(4) (1; models
        without held variables only).  An importer may change it before
        initialisation.
    solver_step : float, optional
        Start value of the ``solver_step`` parameter (largest internal RK4
        sub-step of Co-Simulation; the first step tried by Dormand-Prince), s.
        Default :func:`default_solver_step`.
    tolerance : float
        Start value of the ``tolerance`` parameter: relative tolerance of
        Dormand-Prince (absolute: tolerance times each state's nominal).
    max_substeps : float
        Start value of the ``max_substeps`` parameter: a doStep that needs
        more internal sub-steps (or Dormand-Prince attempts) returns Discard
        instead of blocking (default 1e6).
    params : mapping str -> float, optional
        Parameter start values replacing the model's defaults (each inside
        its declared range).
    identifier : str, optional
        ``modelIdentifier`` (name of the shared library); default from the
        model name.
    description : str, optional
        Model description text; default names the model and its sizes.
    stop_time, step_size : float, optional
        ``DefaultExperiment`` stop time and communication step, s; default
        :func:`default_experiment`.
    author, version, license, copyright : str
        Written into ``modelDescription.xml`` (empty ones are left out);
        ``generationTool`` is ``bondcosim <version>``.

    Returns
    -------
    pathlib.Path
        The FMU written.  Model Exchange (smooth models) has an event
        indicator per switching surface of the laws (:func:`event_indicators`);
        both interfaces provide directional derivatives of derivatives and
        outputs by states and inputs where every law has a symbolic derivative.

    Raises
    ------
    FMUError
        Bad arguments (unknown parameter, version, solver, step, tolerance) or an
        unsupported platform.
    CompilationError
        The C compiler failed.
    """
    if fmi_version not in (2, 3):
        raise FMUError(f"fmi_version must be 2 or 3, got {fmi_version!r}")
    eqs = fmu_equations(_equations_of(model))
    if params:
        unknown = sorted(set(params) - set(eqs.param_values))
        if unknown:
            raise FMUError(f"model {eqs.name!r} has no parameter(s) {', '.join(unknown)}; its "
                           f"parameters are {', '.join(eqs.param_names)}")
        eqs = dataclasses.replace(eqs, param_values={**eqs.param_values,
                                                     **{k: float(v) for k, v in params.items()}})
        try:
            check_param_bounds(eqs, np.array([[eqs.param_values[s.name] for s in eqs.params]]))
        except ParameterError as exc:
            raise FMUError(str(exc)) from None
    step = default_solver_step(eqs) if solver_step is None else float(solver_step)
    if not (step > 0.0 and math.isfinite(step)):
        raise FMUError(f"solver_step must be a positive number of seconds, got {solver_step!r}")
    if not (isinstance(max_substeps, (int, float)) and max_substeps >= 1 and math.isfinite(max_substeps)):
        raise FMUError(f"max_substeps must be a finite number >= 1, got {max_substeps!r}")
    if solver not in SOLVERS:
        raise FMUError(f"solver must be one of {', '.join(SOLVERS)}, got {solver!r}")
    if SOLVERS[solver] and eqs.held:
        raise FMUError(f"solver {solver!r} is not offered by {eqs.name!r}: its held variables "
                       f"({', '.join(eqs.held_names)}) need the fixed-step solver rk4")
    if not (isinstance(tolerance, (int, float)) and tolerance > 0 and math.isfinite(tolerance)):
        raise FMUError(f"tolerance must be a positive number, got {tolerance!r}")
    folder = binary_platform(fmi_version)
    ident = identifier or model_identifier(eqs.name)
    if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", ident):
        raise FMUError(f"identifier must be a C identifier (letters, digits, _; not first a digit), "
                       f"it names the shared library; got {ident!r}")
    model_exchange = eqs.is_smooth
    indicators = event_indicators(eqs)
    variables = variable_layout(eqs, step, fmi_version=fmi_version, max_substeps=float(max_substeps),
                                tolerance=float(tolerance), solver=SOLVERS[solver],
                                indicators=tuple(_switch_text(g, sw) for g, sw in indicators))
    partials = _partials(eqs)
    kernels = "\n".join([generate_source(eqs, part="main"), guard_source(eqs),
                         indicator_source(eqs, [g for g, _ in indicators]) if indicators else "",
                         partials])
    description = description or (f"{eqs.name}: {len(eqs.states)} states, {len(eqs.inputs)} inputs, "
                                  f"{len(eqs.outputs)} outputs (bond graph exported by bondcosim)")
    token = "{" + str(uuid.uuid5(uuid.NAMESPACE_URL, "bondcosim:" + hashlib.sha256(
        "\0".join([kernels, repr(variables), str(fmi_version), ident, str(model_exchange)]).encode()
    ).hexdigest())) + "}"
    header = model_header(eqs, variables, token=token, model_exchange=model_exchange,
                          n_indicators=len(indicators), directional=bool(partials))
    experiment = default_experiment(eqs, step)
    for key, value in (("stopTime", stop_time), ("stepSize", step_size)):
        if value is not None:
            if not (isinstance(value, (int, float)) and value > 0 and math.isfinite(value)):
                raise FMUError(f"{'stop_time' if key == 'stopTime' else 'step_size'} must be a "
                               f"positive number of seconds, got {value!r}")
            experiment[key] = float(value)
    meta = {"author": author, "version": version, "license": license, "copyright": copyright}
    xml = model_description_xml(variables, version=fmi_version, name=eqs.name, identifier=ident,
                                token=token, description=description,
                                model_exchange=model_exchange, date="2000-01-01T00:00:00Z",
                                experiment=experiment, meta=meta,
                                sources=compiled_sources(fmi_version),
                                n_indicators=len(indicators), directional=bool(partials))
    generated = {"model.h": header, "model_kernels.c": kernels}
    binary = compile_fmu_binary(generated, fmi_version=fmi_version, identifier=ident)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
        def add(name, data):
            info = zipfile.ZipInfo(name, _EPOCH)
            info.compress_type = zipfile.ZIP_DEFLATED
            info.external_attr = 0o644 << 16
            z.writestr(info, data)
        add("modelDescription.xml", xml)
        add(f"binaries/{folder}/{ident}.so", binary)
        for name, text in source_files(generated, fmi_version=fmi_version, identifier=ident).items():
            add(name, text)
    return path
