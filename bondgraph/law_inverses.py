"""The unique inverse of an element's law, solved once per machine.

An R given by its effort law ``e = g(f)`` may take either causality when sympy finds exactly one
solution ``f = g^{-1}(e)``.  ``sympy.solve`` takes 0.4-1.2 s on a smoothed friction law
``c tanh(f/v) = e`` (it finds two solutions and checks both), and a diagnosis derives such a law
for every friction candidate of every run.  So the answer is kept: in memory, and on disk next to
the compiled libraries (``$BONDCOSIM_CACHE``, else ``~/.cache/bondcosim``, folder ``inverses``),
keyed by the sha256 of the law, the two port variables and the sympy version.

What is kept is exactly what the element uses: "no unique inverse", or the one solution as its
``srepr``, stored only when reading it back gives an equal expression (symbols, assumptions and
numbers included), so a law read from the cache derives the same equations as one solved anew.
"""
from __future__ import annotations

import hashlib
import os
import tempfile
from pathlib import Path

import sympy as sp

__all__ = ["unique_inverse"]

_MEMORY: dict = {}
_MEMORY_KEPT = 256
_NONE = "none"


def _folder() -> Path:
    env = os.environ.get("BONDCOSIM_CACHE")
    return (Path(env).expanduser() if env else Path.home() / ".cache" / "bondcosim") / "inverses"


#: functions without an algebraic inverse; a law with two or more distinct ones of the variable
#: has no closed-form inverse, and sympy's search for one can take all the memory there is
TRANSCENDENTAL = (sp.exp, sp.log, sp.sin, sp.cos, sp.tan, sp.sinh, sp.cosh, sp.tanh, sp.asin, sp.acos,
                  sp.atan, sp.asinh, sp.acosh, sp.atanh, sp.erf)


def _transcendental_terms(law, known) -> int:
    """How many distinct transcendental functions of `known` `law` holds (``exp(-(f/v)^2)`` and
    ``tanh(f/w)``: two)."""
    return len({a for a in law.atoms(*TRANSCENDENTAL) if a.has(known)})


def _solve(law, unknown, known):
    solutions = []
    # a Stribeck law with numbers, (0.0036 + 0.0043 exp(-(f/0.0099)^2)) tanh(f/0.0011), took
    # sympy.solve past 24 GB: such laws stay in the causality they are given
    if (not law.has(sp.Piecewise, sp.Heaviside, sp.Max, sp.Min, sp.floor, sp.ceiling)
            and _transcendental_terms(law, known) < 2):
        try:   # switched laws are not inverted: their causality stays as given
            solutions = sp.solve(sp.Eq(law, unknown), known)
        except NotImplementedError:
            solutions = []
    return solutions[0] if len(solutions) == 1 and not solutions[0].has(sp.Piecewise) else None


def _read(path: Path):
    """(found, inverse or None) from a cache file; not found when absent or unreadable."""
    try:
        text = path.read_text()
    except OSError:
        return False, None
    if text == _NONE:
        return True, None
    try:
        return True, sp.sympify(text)
    except (sp.SympifyError, SyntaxError, TypeError, ValueError, NameError):
        return False, None


def _write(path: Path, inverse) -> None:
    text = _NONE if inverse is None else sp.srepr(inverse)
    if inverse is not None:
        try:
            if sp.sympify(text) != inverse:    # would not read back the same: not kept
                return
        except (sp.SympifyError, SyntaxError, TypeError, ValueError, NameError):
            return
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=".inv-")
        with os.fdopen(fd, "w") as fh:
            fh.write(text)
        os.replace(tmp, path)         # atomic: a concurrent reader sees all or nothing
    except OSError:
        pass                          # a read-only cache: solved again next time


def unique_inverse(law, unknown, known):
    """`known` from ``law = unknown`` when sympy finds exactly one solution (without Piecewise),
    else None; switched laws (Piecewise, Heaviside, Max, Min, floor, ceiling) and laws with two
    or more transcendental functions of `known` (:data:`TRANSCENDENTAL`) give None."""
    key = (law, unknown, known)
    if key in _MEMORY:
        return _MEMORY[key]
    digest = hashlib.sha256("\0".join([sp.__version__, sp.srepr(law), sp.srepr(unknown),
                                       sp.srepr(known)]).encode()).hexdigest()[:40]
    path = _folder() / f"{digest}.txt"
    found, inverse = _read(path)
    if not found:
        inverse = _solve(law, unknown, known)
        _write(path, inverse)
    if len(_MEMORY) >= _MEMORY_KEPT:
        _MEMORY.clear()
    _MEMORY[key] = inverse
    return inverse
