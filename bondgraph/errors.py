"""Exceptions of bondcosim.

Every error the project raises derives from :class:`BondcosimError`, and each
also derives from the builtin it refines, so ``except ValueError`` keeps
working for callers who do not know our types.  Exceptions carry the
offending names as attributes, not only in their message.
"""
from __future__ import annotations

__all__ = [
    "BondcosimError",
    "GraphError",
    "UnknownElementKindError",
    "DuplicateNameError",
    "PortError",
    "JunctionError",
    "ExpressionError",
    "ParameterError",
    "CausalityError",
    "DerivationError",
    "SchemaError",
    "CompilationError",
    "SimulationError",
    "UnknownNameError",
    "FMUError",
    "UnitError",
    "DomainError",
    "FMUStepDiscarded",
    "CosimError",
    "AlgebraicLoopError",
    "EstimatorError",
]


class BondcosimError(Exception):
    """Base class of every error raised by bondcosim."""


class GraphError(BondcosimError, ValueError):
    """A bond graph is malformed.

    Attributes
    ----------
    problems : list of str
        Every problem found (validation collects them all before raising).
    """

    def __init__(self, message: str, problems: list[str] | None = None):
        self.problems = list(problems) if problems else [message]
        super().__init__(message)


class UnknownElementKindError(GraphError):
    """An element kind name that bondcosim does not know."""

    def __init__(self, kind: str, known: list[str]):
        self.kind = kind
        self.known = list(known)
        super().__init__(
            f"unknown element kind {kind!r}; expected one of {', '.join(sorted(known))}"
        )


class DuplicateNameError(GraphError):
    """Two elements, bonds or symbols share a name."""

    def __init__(self, name: str, what: str):
        self.name = name
        super().__init__(f"duplicate name {name!r}: {what}")


class PortError(GraphError):
    """A bond refers to a missing port, or a port is used twice."""

    def __init__(self, message: str, element: str | None = None, port: str | None = None):
        self.element = element
        self.port = port
        super().__init__(message)


class JunctionError(GraphError):
    """A junction has fewer than two bonds, or an element has unconnected ports."""

    def __init__(self, message: str, element: str | None = None, problems: list[str] | None = None):
        self.element = element
        super().__init__(message, problems)


class ExpressionError(BondcosimError, ValueError):
    """An expression does not parse or names unknown symbols.

    Attributes
    ----------
    owner : str
        What the expression belongs to (element, output or input name).
    expression : str
        The text as given.
    unknown : list of str
        Names the expression uses that the graph does not define.
    """

    def __init__(self, message: str, owner: str = "", expression: str = "",
                 unknown: list[str] | None = None):
        self.owner = owner
        self.expression = expression
        self.unknown = list(unknown or [])
        super().__init__(message)


class ParameterError(BondcosimError, ValueError):
    """A parameter value that is not a finite real number, or an unknown parameter."""

    def __init__(self, message: str, name: str = ""):
        self.name = name
        super().__init__(message)


class ArgumentError(BondcosimError, ValueError):
    """A function argument with a wrong value or shape.

    Attributes
    ----------
    name : str
        The offending argument (``"t_span"``, ``"x0"``, ``"output_interval"``...), "" if unknown.
    """

    def __init__(self, message: str, name: str = ""):
        self.name = str(name)
        super().__init__(message)


class ArgumentTypeError(BondcosimError, TypeError):
    """A function argument of the wrong type (``name``: the argument)."""

    def __init__(self, message: str, name: str = ""):
        self.name = str(name)
        super().__init__(message)


class MissingFileError(BondcosimError, FileNotFoundError):
    """A file the caller named does not exist (``path``: the file)."""

    def __init__(self, message: str, path: str = ""):
        self.path = str(path)
        super().__init__(message)


class OutputTooLargeError(BondcosimError, MemoryError):
    """A result that would not fit in memory, refused before any work.

    Attributes
    ----------
    n_samples, n_signals : int
        Size of the result asked for.
    n_bytes : int
        Memory it needs.
    available : int
        Memory available for it, bytes.
    """

    def __init__(self, message: str, *, n_samples: int, n_signals: int, n_bytes: int, available: int):
        self.n_samples, self.n_signals = int(n_samples), int(n_signals)
        self.n_bytes, self.available = int(n_bytes), int(available)
        super().__init__(message)


class OptionalDependencyError(BondcosimError, ImportError):
    """A feature needs a package that is not installed (``package``: its name)."""

    def __init__(self, message: str, package: str = ""):
        self.package = package
        super().__init__(message, name=package or None)


__all__ += ["ArgumentError", "ArgumentTypeError", "MissingFileError", "OutputTooLargeError",
            "OptionalDependencyError"]


class CausalityError(BondcosimError, ValueError):
    """Causality cannot be assigned: conflicts, named by element and bond.

    Attributes
    ----------
    conflicts : list of Conflict-like objects
        Each with ``element``, ``bonds`` and ``reason`` attributes.
    """

    def __init__(self, conflicts):
        self.conflicts = list(conflicts)
        lines = [f"  - {c}" for c in self.conflicts]
        n = len(self.conflicts)
        super().__init__(
            f"{n} causal conflict{'s' if n != 1 else ''}:\n" + "\n".join(lines)
        )


class DerivationError(BondcosimError, ValueError):
    """State equations cannot be derived for a structural reason named in the message."""

    def __init__(self, message: str, element: str | None = None):
        self.element = element
        super().__init__(message)


class SchemaError(GraphError):
    """A JSON graph file does not match the documented schema.

    Attributes
    ----------
    path : str
        JSON path of the offending entry, e.g. ``elements[3].kind``.
    """

    def __init__(self, message: str, path: str = ""):
        self.path = path
        super().__init__(f"{path}: {message}" if path else message)


class CompilationError(BondcosimError, RuntimeError):
    """The system C compiler failed on generated code (its output is attached)."""

    def __init__(self, message: str, output: str = ""):
        self.output = output
        super().__init__(message + (f"\n{output}" if output else ""))


class SimulationError(BondcosimError, RuntimeError):
    """A simulation failed (solver failure, NaN state, unsolvable algebraic loop)."""

    def __init__(self, message: str, time: float | None = None):
        self.time = time
        super().__init__(message)


class UnknownNameError(BondcosimError, ValueError):
    """A name (input, state) the model does not have.

    Attributes
    ----------
    kind : str
        ``"input"`` or ``"state"``.
    name : str
        The unknown name.
    known : list of str
        The names the model has.
    """

    def __init__(self, kind: str, name: str, known, model: str = ""):
        self.kind, self.name, self.known = kind, name, list(known)
        where = f" of model {model!r}" if model else ""
        super().__init__(f"unknown {kind} {name!r}{where}; known {kind}s are "
                         f"{', '.join(self.known) or '(none)'}")


class UnknownSignalError(UnknownNameError, KeyError):
    """A signal name a result does not have (``result["nope"]``): an
    :class:`UnknownNameError` and a ``KeyError``, as mapping lookups raise."""

    def __init__(self, name: str, known, message: str | None = None):
        super().__init__("signal", name, known)
        if message:
            self.args = (message,)

    def __str__(self) -> str:   # KeyError would quote the message
        return Exception.__str__(self)


__all__ += ["UnknownSignalError"]


class FMUError(BondcosimError, RuntimeError):
    """An FMU could not be exported, opened or run.

    Attributes
    ----------
    path : str
        The FMU file concerned ("" when there is none yet).
    """

    def __init__(self, message: str, path: str = ""):
        self.path = str(path)
        super().__init__(message)


class UnitError(BondcosimError, ValueError):
    """A unit that is unknown, or two units that cannot be converted into each other.

    Attributes
    ----------
    unit_from, unit_to : str
        The two units concerned (``unit_to`` is "" when only one unit was parsed).
    """

    def __init__(self, message: str, unit_from: str = "", unit_to: str = ""):
        self.unit_from = unit_from
        self.unit_to = unit_to
        super().__init__(message)


class DomainError(SimulationError):
    """A model variable left its physical domain (a :class:`~bondgraph.guards.Guard`):
    a chamber volume or an absolute pressure below zero, a non-finite value.

    Attributes
    ----------
    variable : str
        The guarded quantity (or state) named in the message.
    value : float
        Its value, in its unit.
    time : float
        When, s.
    owner : str
        The element (or ``"graph"``) that declared the guard.
    """

    def __init__(self, message: str, *, variable: str, value: float, time: float, owner: str = ""):
        self.variable, self.value, self.owner = variable, value, owner
        super().__init__(message, time=time)


class FMUStepDiscarded(FMUError):
    """An FMU's doStep returned Discard (the FMU stays at the step's start): a
    physical-domain guard, a non-finite state or output, too many sub-steps.

    Attributes
    ----------
    component : str
        The co-simulation component (instance name).
    time : float
        Start of the discarded step, s.
    step : float
        Its length, s.
    reason : str
        The FMU's logged message ("" if it logged none).
    """

    def __init__(self, message: str, *, component: str, time: float, step: float, reason: str = "",
                 path: str = ""):
        self.component, self.time, self.step, self.reason = component, time, step, reason
        super().__init__(message, path=path)


class CosimError(BondcosimError, ValueError):
    """A co-simulation is set up wrongly: an unknown component or port, a
    connection between ports of different units, an input driven twice."""

    def __init__(self, message: str, ports=()):
        self.ports = tuple(ports)
        super().__init__(message)


class AlgebraicLoopError(CosimError):
    """Direct-feedthrough ports form a loop the master cannot order.

    Attributes
    ----------
    ports : tuple of str
        The loop as ``component.port`` names, in signal order.
    """


class EstimatorError(BondcosimError, ValueError):
    """An estimator is set up wrongly or fails at a step.

    Set-up problems: a matrix of the wrong shape, not symmetric, not positive
    (semi)definite or not finite; a measurement of the wrong shape or not
    finite.  Failures at a step: a covariance that is no longer positive
    definite (its Cholesky factorisation fails), a model that returns
    non-finite states.

    Attributes
    ----------
    name : str
        The offending matrix or argument: ``"x0"``, ``"P0"``, ``"Q"``, ``"R"``,
        ``"z"``, ``"u"``, ``"P"`` (posterior), ``"P_prior"``, ``"S"``
        (innovation covariance), ``"fx"``, ``"hx"``...
    step : int or None
        Filter step (number of predictions made) at which it happened.
    time : float or None
        Filter time, s, when known.
    problems : list of str
        Every problem found (validation collects them all before raising).
    """

    def __init__(self, message: str, name: str = "", *, step: int | None = None,
                 time: float | None = None, problems: list[str] | None = None):
        self.name = str(name)
        self.step = step
        self.time = time
        self.problems = list(problems) if problems else [message]
        super().__init__(message)


class UnobservableModeError(EstimatorError):
    """A mode of ``A`` that the measurements ``C`` cannot see (and that is not
    stable, so no observer can estimate it).

    Attributes
    ----------
    eigenvalue : complex
        The unobservable eigenvalue of ``A`` (continuous: rad/s; discrete: per step).
    direction : ndarray, shape (n_states,)
        Its eigenvector (unit 2-norm), the state combination that is invisible.
    states : tuple of str
        Names of the states that dominate `direction` (empty without names).
    """

    def __init__(self, message: str, eigenvalue: complex, direction, states=(), name: str = "C"):
        self.eigenvalue = complex(eigenvalue)
        self.direction = direction
        self.states = tuple(states)
        super().__init__(message, name=name)


class UncontrollableModeError(EstimatorError):
    """A mode of ``A`` that the inputs ``B`` cannot move (and that is not
    stable, so no state feedback can stabilise it).  Attributes as
    :class:`UnobservableModeError`."""

    def __init__(self, message: str, eigenvalue: complex, direction, states=(), name: str = "B"):
        self.eigenvalue = complex(eigenvalue)
        self.direction = direction
        self.states = tuple(states)
        super().__init__(message, name=name)


__all__ += ["UnobservableModeError", "UncontrollableModeError"]
