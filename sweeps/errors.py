"""Exceptions of the sweeps package.

All derive from :class:`bondgraph.errors.BondcosimError` and from ``ValueError``
(or ``RuntimeError`` for an engine failure), so the CLI reports them in one line.
Each carries the offending thing as attributes, not only in its message.
"""
from __future__ import annotations

from bondgraph.errors import BondcosimError

__all__ = ["SweepError", "SpecError", "DistributionError", "MetricError", "StoreError", "EngineError"]


class SweepError(BondcosimError, ValueError):
    """A sweep cannot be set up (reason in the message)."""


class SpecError(SweepError):
    """A sweep specification (file or object) with problems; every problem is listed.

    Attributes
    ----------
    source : str
        The spec file, or ``"spec"`` for one built in Python.
    problems : list of str
        One line per problem, each naming the offending key.
    """

    def __init__(self, source: str, problems):
        self.source = str(source)
        self.problems = list(problems)
        lines = "\n  ".join(self.problems)
        super().__init__(f"{self.source}: {len(self.problems)} problem(s):\n  {lines}")


class DistributionError(SweepError):
    """A distribution or grid text that does not parse.

    Attributes
    ----------
    name : str
        The parameter it was given for.
    text : str
        The offending text.
    """

    def __init__(self, name: str, text: str, reason: str):
        self.name, self.text = str(name), str(text)
        super().__init__(f"parameter {self.name!r}: cannot read {self.text!r}: {reason}. Expected one of "
                         "uniform(LOW, HIGH), normal(MEAN, STD), lognormal(MU, SIGMA), grid(V1, V2, ...), "
                         "linspace(START, STOP, N), geomspace(START, STOP, N) or a number, each optionally "
                         "'*nominal' (relative to the parameter's default)")


class MetricError(SweepError):
    """A requested metric that a run's result does not have.

    Attributes
    ----------
    name : str
    known : list of str
    """

    def __init__(self, name: str, known, target: str):
        self.name, self.known = str(name), sorted(known)
        super().__init__(f"metric {self.name!r} is not in the results of {target}; known metrics are "
                         f"{', '.join(self.known) or '(none)'}")


class StoreError(SweepError):
    """A results directory that does not fit the sweep (another spec, or not a sweep directory).

    Attributes
    ----------
    path : str
    """

    def __init__(self, path, message: str):
        self.path = str(path)
        super().__init__(f"{self.path}: {message}")


class EngineError(BondcosimError, RuntimeError):
    """The Dask cluster could not be started or reached.

    Attributes
    ----------
    address : str
        The scheduler address ("" for a local cluster).
    """

    def __init__(self, address: str, message: str):
        self.address = str(address)
        super().__init__(message)
