"""What a sweep varies: a parameter's distribution (Monte-Carlo) or its grid, parsed from text.

Text forms (``A1=normal(1, 0.1)*nominal`` on the command line, ``A1 = "..."`` in a spec file):

==============================  ==================================================================
``uniform(LOW, HIGH)``          :math:`U(\\mathrm{low}, \\mathrm{high})`
``normal(MEAN, STD)``           :math:`N(\\mathrm{mean}, \\mathrm{std}^2)`
``lognormal(MU, SIGMA)``        :math:`\\exp N(\\mu, \\sigma^2)` (mu, sigma of the logarithm)
``grid(V1, V2, ...)``           the listed values
``linspace(START, STOP, N)``    N values evenly spaced, ends included
``geomspace(START, STOP, N)``   N values evenly spaced in log, ends included
a number                        that value
==============================  ==================================================================

Each may end in ``*nominal`` (or start with ``nominal*``): the drawn or listed
value multiplies the parameter's default (its nominal), so ``normal(1, 0.1)*nominal``
is a 10 % spread about it.  Values are in the parameter's SI unit otherwise.

Examples
--------
>>> law = parse("A1", "normal(1, 0.1)*nominal")
>>> law.kind, law.args, law.relative
('normal', (1.0, 0.1), True)
>>> parse("k", "linspace(1, 3, 3)").values(nominal=2.0)
(1.0, 2.0, 3.0)
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Literal

import numpy as np

from .errors import DistributionError

__all__ = ["Distribution", "Grid", "parse", "RANDOM_KINDS", "GRID_KINDS"]

#: Random laws and their argument names.
RANDOM_KINDS = {"uniform": ("low", "high"), "normal": ("mean", "std"), "lognormal": ("mu", "sigma")}
#: Grid forms.
GRID_KINDS = ("grid", "linspace", "geomspace", "value")

_CALL = re.compile(r"^\s*(?:nominal\s*\*\s*)?([a-z]+)\s*\((.*)\)\s*(\*\s*nominal\s*)?$")


@dataclass(frozen=True)
class Distribution:
    """A random law for one parameter.

    Attributes
    ----------
    kind : {"uniform", "normal", "lognormal"}
    args : tuple of float
        ``(low, high)``, ``(mean, std)`` or ``(mu, sigma)``.
    relative : bool
        The draw multiplies the parameter's nominal value.
    text : str
        The text it was read from (for records and messages).
    """

    kind: Literal["uniform", "normal", "lognormal"]
    args: tuple
    relative: bool = False
    text: str = ""

    def sample(self, rng: np.random.Generator, *, nominal: float) -> float:
        """One draw from `rng`, times `nominal` if :attr:`relative`."""
        a, b = self.args
        draw = {"uniform": rng.uniform, "normal": rng.normal, "lognormal": rng.lognormal}[self.kind](a, b)
        return float(draw * nominal if self.relative else draw)


@dataclass(frozen=True)
class Grid:
    """A list of values for one parameter (a grid axis).

    Attributes
    ----------
    points : tuple of float
    relative : bool
        Each point multiplies the parameter's nominal value.
    text : str
    """

    points: tuple
    relative: bool = False
    text: str = ""

    def values(self, *, nominal: float) -> tuple:
        """The axis values in the parameter's unit."""
        return tuple(float(p * nominal) if self.relative else float(p) for p in self.points)


def _numbers(name: str, text: str, inner: str) -> list[float]:
    parts = [p.strip() for p in inner.split(",")] if inner.strip() else []
    try:
        return [float(p) for p in parts]
    except ValueError:
        bad = next(p for p in parts if not _is_float(p))
        raise DistributionError(name, text, f"{bad!r} is not a number") from None


def _is_float(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def parse(name: str, text) -> Distribution | Grid:
    """Read a distribution or grid for parameter `name` (see the module docstring).

    Parameters
    ----------
    name : str
        The parameter (for messages).
    text : str or float or list of float
        A number or a list (from a spec file) is a grid of those values.

    Returns
    -------
    Distribution or Grid

    Raises
    ------
    DistributionError
        The text does not parse, names an unknown law, has the wrong number of
        arguments or invalid ones (negative spread, N < 1, ...).
    """
    if isinstance(text, bool):
        raise DistributionError(name, str(text), "a boolean is not a value")
    if isinstance(text, (int, float)):
        return Grid((float(text),), False, str(text))
    if isinstance(text, (list, tuple)):
        values = _numbers(name, str(text), ",".join(str(v) for v in text))
        if not values:
            raise DistributionError(name, str(text), "an empty list")
        return Grid(tuple(values), False, str(list(text)))
    text = str(text)
    stripped = text.strip()
    if stripped.startswith("[") and stripped.endswith("]"):        # a list's text (SweepSpec.to_dict)
        values = _numbers(name, text, stripped[1:-1])
        if not values:
            raise DistributionError(name, text, "an empty list")
        return Grid(tuple(values), False, text)
    relative_number = re.match(r"^\s*(?:nominal\s*\*\s*)?([^*()]+?)\s*(\*\s*nominal\s*)?$", stripped)
    if relative_number and _is_float(relative_number.group(1)):
        rel = stripped.startswith("nominal") or relative_number.group(2) is not None
        return Grid((float(relative_number.group(1)),), rel, text)
    match = _CALL.match(stripped)
    if not match:
        raise DistributionError(name, text, "not LAW(ARGS) with an optional '*nominal'")
    kind, inner = match.group(1), match.group(2)
    relative = stripped.startswith("nominal") or match.group(3) is not None
    args = _numbers(name, text, inner)
    if not all(np.isfinite(args)):
        raise DistributionError(name, text, "arguments must be finite")
    if kind in RANDOM_KINDS:
        if len(args) != 2:
            raise DistributionError(name, text, f"{kind} takes 2 arguments ({', '.join(RANDOM_KINDS[kind])}), "
                                                f"got {len(args)}")
        if kind == "uniform" and not args[0] < args[1]:
            raise DistributionError(name, text, "uniform needs LOW < HIGH")
        if kind in ("normal", "lognormal") and args[1] < 0:
            raise DistributionError(name, text, f"{kind} needs a spread >= 0")
        return Distribution(kind, tuple(args), relative, text)
    if kind == "grid":
        if not args:
            raise DistributionError(name, text, "grid needs at least one value")
        return Grid(tuple(args), relative, text)
    if kind in ("linspace", "geomspace"):
        if len(args) != 3 or args[2] != int(args[2]) or args[2] < 1:
            raise DistributionError(name, text, f"{kind} takes START, STOP and a whole N >= 1")
        if kind == "geomspace" and args[0] * args[1] <= 0:
            raise DistributionError(name, text, "geomspace needs START and STOP of the same sign, non-zero")
        points = getattr(np, kind)(args[0], args[1], int(args[2]))
        return Grid(tuple(float(p) for p in points), relative, text)
    raise DistributionError(name, text, f"unknown law {kind!r}")
