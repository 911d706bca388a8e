"""Exceptions of the diagnosis package.

All derive from :class:`bondgraph.errors.BondcosimError` and from the builtin
they refine (``ValueError``), so ``except ValueError`` keeps working.  Each
carries the offending names as attributes, not only in its message.
Other diagnosis modules append their own classes here.
"""
from __future__ import annotations

from bondgraph.errors import BondcosimError, SimulationError, UnknownNameError
from bondgraph.errors import UnitError as CoreUnitError

__all__ = ["DiagnosisError", "BenchmarkError", "UnitError", "RecordingError", "UnknownColumnError", "UnknownCaseError",
           "UnknownFieldError", "BondcosimError", "SimulationError", "UnknownNameError", "CoreUnitError"]


class DiagnosisError(BondcosimError, ValueError):
    """A diagnosis cannot be set up or carried out (reason in the message)."""


class UnitError(DiagnosisError, CoreUnitError):
    """A unit that is unknown, or two units that cannot be converted into each other
    (the core's :class:`bondgraph.errors.UnitError`, raised by diagnosis as a DiagnosisError).

    Attributes
    ----------
    unit_from, unit_to : str
        The two units concerned (``unit_to`` is "" when only one unit was parsed).
    """


class RecordingError(DiagnosisError):
    """A recording that cannot be used as it is.

    Attributes
    ----------
    source : str
        The file (or ``"arrays"``) the recording came from.
    column : str or None
        The offending column, when one is concerned.
    rows : list of int
        The offending data rows (0-based, header excluded), when known.
    """

    def __init__(self, message: str, source: str = "", column: str | None = None,
                 rows=()):
        self.source = str(source)
        self.column = column
        self.rows = [int(r) for r in rows]
        super().__init__(message)


class UnknownColumnError(UnknownNameError, RecordingError):
    """A column the recording does not have (an :class:`UnknownNameError` with
    ``kind == "column"``, and a :class:`RecordingError`).

    Attributes
    ----------
    name : str
        The missing column.
    known : list of str
        The recording's columns.
    source : str
        The recording's file.
    """

    def __init__(self, name: str, known, source: str = "", wanted_for: str = ""):
        self.kind, self.name, self.known = "column", name, list(known)
        self.source, self.column, self.rows = str(source), name, []
        why = f" (wanted for {wanted_for})" if wanted_for else ""
        Exception.__init__(self, f"{source}: no column {name!r}{why}; columns are "
                                 f"{', '.join(self.known) or '(none)'}")


class BenchmarkError(DiagnosisError):
    """The generalisation benchmark could not make a case (an effect that cannot act at a
    place, a truth run that leaves the finite numbers while sizing an effect)."""


class UnknownCaseError(DiagnosisError, KeyError):
    """A diagnosis case, truth-model parameter or element name that does not exist
    (a ``KeyError`` too, as the lookups it replaces raised)."""

    def __str__(self) -> str:   # KeyError would quote the message
        return Exception.__str__(self)


class UnknownFieldError(DiagnosisError, KeyError):
    """A field a diagnosis round does not have, or has not set, read by key
    (a ``KeyError`` too, as the dicts the rounds were raised)."""

    def __str__(self) -> str:   # KeyError would quote the message
        return Exception.__str__(self)
