"""Units: parse unit texts, convert values, and state them in SI base units (FMI ``BaseUnit``).

One unit grammar for every layer: the FMU exporter writes each unit's base-unit
exponents, factor and offset (:func:`base_unit`), the co-simulation master
converts between connected ports, diagnosis converts recorded columns.

A unit text is a product of factors separated by spaces, ``*`` or ``·``,
optionally with one ``/`` after which every factor is in the denominator
(``"J/(kg K)"``, ``"N m/rad"``, ``"m/s^2"``).  A factor is a symbol with an
optional SI prefix (``kPa``, ``mm``, ``ms``, ``µm``) and an optional integer
exponent (``m^2``, ``m**2``, ``s-1``).  Dimensions are tracked over the base
``(kg, m, s, A, K, mol, cd, rad)`` -- FMI's BaseUnit exponents; angles are a
dimension of their own, so
``rad -> m`` is refused while ``deg/s -> rad/s`` converts.  Absolute
temperatures in ``degC`` convert to ``K`` (offset) only as a lone factor.

Examples
--------
>>> float(convert(2.0, "bar", "Pa"))
200000.0
>>> convert([90.0, 180.0], "deg", "rad").round(6).tolist()
[1.570796, 3.141593]
>>> float(convert(1500.0, "N mm", "N m"))
1.5
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np

from .errors import UnitError

__all__ = ["Unit", "parse_unit", "convert", "compatible", "base_unit", "BASE_UNITS"]

_BASE = ("kg", "m", "s", "A", "K", "mol", "cd", "rad")
#: The SI base units (and rad), in the order of :attr:`Unit.dimension`; FMI's BaseUnit attributes.
BASE_UNITS = _BASE


def _dim(**exps) -> tuple[int, ...]:
    return tuple(int(exps.get(b, 0)) for b in _BASE)


_N = _dim(kg=1, m=1, s=-2)
_J = _dim(kg=1, m=2, s=-2)
_V = _dim(kg=1, m=2, s=-3, A=-1)
#: symbol -> (scale to SI, dimension exponents); prefixes are allowed on all but a few.
_SYMBOLS: dict[str, tuple[float, tuple[int, ...]]] = {
    "1": (1.0, _dim()), "-": (1.0, _dim()), "%": (0.01, _dim()),
    "m": (1.0, _dim(m=1)), "g": (1e-3, _dim(kg=1)), "s": (1.0, _dim(s=1)),
    "A": (1.0, _dim(A=1)), "K": (1.0, _dim(K=1)), "mol": (1.0, _dim(mol=1)),
    "rad": (1.0, _dim(rad=1)), "deg": (math.pi / 180.0, _dim(rad=1)),
    "°": (math.pi / 180.0, _dim(rad=1)), "rev": (2.0 * math.pi, _dim(rad=1)),
    "rpm": (2.0 * math.pi / 60.0, _dim(rad=1, s=-1)),
    "min": (60.0, _dim(s=1)), "h": (3600.0, _dim(s=1)),
    "Hz": (1.0, _dim(s=-1)), "N": (1.0, _N), "Nm": (1.0, _dim(kg=1, m=2, s=-2)),
    "Pa": (1.0, _dim(kg=1, m=-1, s=-2)), "bar": (1e5, _dim(kg=1, m=-1, s=-2)),
    "atm": (101325.0, _dim(kg=1, m=-1, s=-2)), "psi": (6894.757293168, _dim(kg=1, m=-1, s=-2)),
    "J": (1.0, _J), "W": (1.0, _dim(kg=1, m=2, s=-3)), "V": (1.0, _V),
    "ohm": (1.0, _dim(kg=1, m=2, s=-3, A=-2)), "Ohm": (1.0, _dim(kg=1, m=2, s=-3, A=-2)),
    "Ω": (1.0, _dim(kg=1, m=2, s=-3, A=-2)), "F": (1.0, _dim(kg=-1, m=-2, s=4, A=2)),
    "H": (1.0, _dim(kg=1, m=2, s=-2, A=-2)), "C": (1.0, _dim(A=1, s=1)),
    "L": (1e-3, _dim(m=3)), "l": (1e-3, _dim(m=3)),
    "cd": (1.0, _dim(cd=1)), "Wb": (1.0, _dim(kg=1, m=2, s=-2, A=-1)),
    "S": (1.0, _dim(kg=-1, m=-2, s=3, A=2)),
}
_NO_PREFIX = {"1", "-", "%", "deg", "°", "rev", "rpm", "min", "h", "atm", "psi", "kg"}
_PREFIXES = {"Y": 1e24, "Z": 1e21, "E": 1e18, "P": 1e15, "T": 1e12, "G": 1e9, "M": 1e6,
             "k": 1e3, "h": 1e2, "da": 1e1, "d": 1e-1, "c": 1e-2, "m": 1e-3, "u": 1e-6,
             "µ": 1e-6, "μ": 1e-6, "n": 1e-9, "p": 1e-12, "f": 1e-15}
_OFFSET_UNITS = {"degC": 273.15, "°C": 273.15}
_FACTOR = re.compile(r"^(?P<sym>[^\d^*+-]+|1|-)(?:(?:\^|\*\*)?(?P<exp>[+-]?\d+))?$")


@dataclass(frozen=True)
class Unit:
    """A parsed unit: ``value_SI = scale * value + offset``.

    Parameters
    ----------
    text : str
        The unit as written.
    scale : float
        Factor to the coherent SI unit of the same dimension.
    dimension : tuple of int
        Exponents of ``(kg, m, s, A, K, mol, cd, rad)``.
    offset : float
        Additive offset to SI (only ``degC``: 273.15 K).
    """

    text: str
    scale: float
    dimension: tuple[int, ...]
    offset: float = 0.0

    def describe_dimension(self) -> str:
        """The dimension in base units, e.g. ``'kg m s^-2'`` (``'1'`` for none)."""
        parts = [b if e == 1 else f"{b}^{e}" for b, e in zip(_BASE, self.dimension) if e]
        return " ".join(parts) or "1"


def _factor(token: str, whole: str) -> tuple[float, tuple[int, ...]]:
    match = _FACTOR.match(token)
    if not match:
        raise UnitError(f"unit {whole!r}: cannot read the factor {token!r}", unit_from=whole)
    sym, exp = match["sym"], int(match["exp"] or 1)
    if sym == "kg":
        scale, dim = 1.0, _dim(kg=1)
    elif sym in _SYMBOLS:
        scale, dim = _SYMBOLS[sym]
    else:
        for prefix, factor in sorted(_PREFIXES.items(), key=lambda kv: -len(kv[0])):
            base = sym[len(prefix):]
            if sym.startswith(prefix) and base in _SYMBOLS and base not in _NO_PREFIX:
                scale, dim = factor * _SYMBOLS[base][0], _SYMBOLS[base][1]
                break
        else:
            known = ", ".join(sorted(k for k in _SYMBOLS if k not in ("-",)))
            raise UnitError(f"unit {whole!r}: unknown symbol {sym!r}; known symbols (with SI "
                            f"prefixes k, M, m, u, ...) are {known}, kg, degC", unit_from=whole)
    return scale ** exp, tuple(e * exp for e in dim)


def parse_unit(text: str) -> Unit:
    """Parse a unit text (see the module docstring).

    Parameters
    ----------
    text : str
        E.g. ``"kPa"``, ``"N m"``, ``"deg/s"``, ``"J/(kg K)"``; ``""`` or ``"1"``
        is dimensionless.

    Returns
    -------
    Unit

    Raises
    ------
    UnitError
        An unknown symbol or unreadable text (named).
    """
    if not isinstance(text, str):
        raise UnitError(f"unit must be a string; found {text!r}", unit_from=str(text))
    whole = text.strip()
    if whole in _OFFSET_UNITS:
        return Unit(text, 1.0, _dim(K=1), _OFFSET_UNITS[whole])
    if whole in ("", "1"):
        return Unit(text, 1.0, _dim())
    num, _, den = whole.partition("/")
    if "/" in den:
        raise UnitError(f"unit {text!r}: more than one '/'; write the denominator in "
                        f"parentheses, e.g. 'J/(kg K)'", unit_from=text)
    scale, dim = 1.0, [0] * len(_BASE)
    for part, sign in ((num, 1), (den.strip().strip("()"), -1)):
        tokens = [t for t in re.split(r"[\s*·.]+", part.replace("**", "^")) if t]
        if sign == -1 and den and not tokens:
            raise UnitError(f"unit {text!r}: empty denominator", unit_from=text)
        for token in tokens:
            if token in _OFFSET_UNITS:
                raise UnitError(f"unit {text!r}: {token} has an offset and can only stand alone "
                                "(use K in compound units)", unit_from=text)
            s, d = _factor(token, text)
            scale *= s ** sign
            dim = [a + sign * b for a, b in zip(dim, d)]
    return Unit(text, scale, tuple(dim))


def base_unit(text: str) -> tuple[dict[str, int], float, float]:
    """`text` in SI base units, as FMI's ``BaseUnit`` states it.

    .. math:: v_{SI} = \\mathrm{factor} \\cdot v + \\mathrm{offset}

    Parameters
    ----------
    text : str
        A unit text (see the module docstring).

    Returns
    -------
    exponents : dict str -> int
        Non-zero exponents of ``kg, m, s, A, K, mol, cd, rad``.
    factor, offset : float

    Examples
    --------
    >>> base_unit("deg")[0], round(base_unit("deg")[1], 12)
    ({'rad': 1}, 0.01745329252)
    >>> base_unit("bar")
    ({'kg': 1, 'm': -1, 's': -2}, 100000.0, 0.0)
    """
    u = parse_unit(text)
    return {b: e for b, e in zip(_BASE, u.dimension) if e}, u.scale, u.offset


def compatible(unit_a: str, unit_b: str) -> bool:
    """True when the two units have the same dimension (both must parse)."""
    return parse_unit(unit_a).dimension == parse_unit(unit_b).dimension


def convert(values, unit_from: str, unit_to: str) -> np.ndarray:
    """Convert values from one unit to another.

    .. math:: v_{to} = \\frac{s_{from} v + o_{from} - o_{to}}{s_{to}}

    with :math:`s` the scale and :math:`o` the offset to SI of each unit.

    Parameters
    ----------
    values : float or array_like
        Values in `unit_from`.
    unit_from, unit_to : str
        Unit texts (see the module docstring).

    Returns
    -------
    ndarray
        Values in `unit_to` (float64, same shape as `values`).

    Raises
    ------
    UnitError
        An unknown unit, or two units of different dimensions; the message
        names both units and their dimensions.
    """
    try:
        a, b = parse_unit(unit_from), parse_unit(unit_to)
    except UnitError as exc:
        raise UnitError(f"cannot convert {unit_from!r} to {unit_to!r}: {exc}",
                        unit_from=unit_from, unit_to=unit_to) from None
    if a.dimension != b.dimension:
        raise UnitError(f"cannot convert {unit_from!r} to {unit_to!r}: incompatible dimensions "
                        f"({a.describe_dimension()} vs {b.describe_dimension()})",
                        unit_from=unit_from, unit_to=unit_to)
    v = np.asarray(values, dtype=float)
    if a.scale == b.scale and a.offset == b.offset:
        return v.copy()
    return (v * a.scale + a.offset - b.offset) / b.scale
