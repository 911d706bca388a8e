"""Derivatives of switched laws: almost everywhere, and where they fail (kinks).

Constitutive laws of real plants switch: ``sign`` and ``Abs`` in orifice and
friction laws, ``Max``/``Min`` in clipped inputs, ``Piecewise`` tables.  Such a
law is differentiable except on its switching surfaces.
:func:`diff_almost_everywhere` gives the derivative that holds off those
surfaces (each switch frozen as locally constant), and :func:`kinks` finds the
switches that sit exactly on their surface at a given point, so a caller
(linearisation) knows where that derivative is not the derivative and a
one-sided difference is needed instead.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass
from itertools import combinations

import sympy as sp

from .errors import DerivationError

__all__ = ["diff_almost_everywhere", "kinks", "Kink", "SWITCHES", "NotDifferentiable", "switching_surfaces"]

#: Functions treated as locally constant when differentiating.
SWITCHES = (sp.sign, sp.Heaviside, sp.floor, sp.ceiling)


class NotDifferentiable(DerivationError):
    """sympy leaves a derivative unevaluated (raised with the expression in the message)."""


def diff_almost_everywhere(expr, var):
    """:math:`\\partial expr / \\partial var` where every switch is locally constant.

    ``sign``, ``Heaviside``, ``floor`` and ``ceiling`` are frozen as constants
    and ``Abs(g)`` is differentiated as ``sign(g) g``: the derivative that holds
    everywhere except on the switching surfaces, which is what a Newton or
    implicit-solver step needs.  (Plain ``sympy.diff`` leaves ``Derivative(sign(g))``
    unevaluated when it cannot prove ``g`` finite, and yields ``DiracDelta`` otherwise.)

    Results are kept (:data:`_REMEMBERED` of them): exporting, compiling and linearising one
    model differentiate the same laws again, and sympy spends seconds on a PAM's.

    Raises
    ------
    NotDifferentiable
        sympy leaves a ``Derivative`` unevaluated.
    """
    return _diff_almost_everywhere(sp.sympify(expr), sp.sympify(var))


#: how many derivatives :func:`diff_almost_everywhere` keeps
_REMEMBERED = 16384


@functools.lru_cache(maxsize=_REMEMBERED)
def _diff_almost_everywhere(expr, var):
    frozen: dict = {}

    def freeze(node):
        if isinstance(node, sp.Abs):
            g = node.args[0]
            return g * frozen.setdefault(sp.sign(g), sp.Dummy("s"))
        return frozen.setdefault(node, sp.Dummy("s"))

    work = (expr.replace(lambda a: isinstance(a, (*SWITCHES, sp.Abs)), freeze)
            if expr.has(*SWITCHES, sp.Abs) else expr)
    de = sp.diff(work, var)
    back = {d: k for k, d in frozen.items()}
    for _ in range(len(back) + 1):   # keys may hold other frozen switches (nesting)
        if not (de.free_symbols & back.keys()):
            break
        de = de.xreplace(back)
    if de.has(sp.DiracDelta):
        de = de.replace(lambda a: isinstance(a, sp.DiracDelta), lambda a: sp.S.Zero)
    if de.has(sp.Derivative):
        raise NotDifferentiable(f"cannot differentiate {expr} with respect to {var}: sympy "
                                f"leaves {de.atoms(sp.Derivative).pop()} unevaluated")
    return de


@dataclass(frozen=True)
class Kink:
    """A switch on its switching surface at a point.

    Attributes
    ----------
    switch : str
        The switching function (shortened to 120 characters).
    symbols : frozenset of sympy.Symbol
        The variables its switching argument depends on.
    """

    switch: str
    symbols: frozenset

    def __str__(self) -> str:
        return f"{self.switch} (depends on {', '.join(sorted(s.name for s in self.symbols))})"


def _surfaces(node) -> list:
    """Expressions that are zero on `node`'s switching surfaces."""
    if isinstance(node, (sp.sign, sp.Abs, sp.Heaviside)):
        return [node.args[0]]
    if isinstance(node, (sp.Max, sp.Min)):
        return [a - b for a, b in combinations(node.args, 2)]
    if isinstance(node, (sp.floor, sp.ceiling)):
        return [sp.sin(sp.pi * node.args[0])]   # zero at every integer
    if isinstance(node, sp.Piecewise):
        out = []
        for _, cond in node.args:
            if isinstance(cond, sp.core.relational.Relational):
                out.append(cond.lhs - cond.rhs)
            elif isinstance(cond, sp.Basic) and not isinstance(cond, sp.logic.boolalg.BooleanAtom):
                out += [r.lhs - r.rhs for r in cond.atoms(sp.core.relational.Relational)]
        return out
    return []


_SWITCH_TYPES = (sp.sign, sp.Abs, sp.Heaviside, sp.Max, sp.Min, sp.floor, sp.ceiling, sp.Piecewise)


def switching_surfaces(exprs, varying) -> list[tuple]:
    """Every switching surface of `exprs`: ``(g, switch)`` with ``g`` zero on the surface
    and changing sign across it (``sign(g)``, ``Abs(g)``, ``Heaviside(g)``; ``a - b`` for
    ``Max(a, b)``/``Min(a, b)``; ``lhs - rhs`` for each inequality of a ``Piecewise``;
    ``sin(pi g)`` for ``floor(g)``), the zero crossings of a Model Exchange event indicator.

    Parameters
    ----------
    exprs : iterable of sympy.Expr
    varying : set of sympy.Symbol
        Symbols that change during a simulation (time, states, inputs, algebraic
        unknowns, assignment names); a surface over none of them never moves.

    Returns
    -------
    list of (sympy.Expr, sympy.Expr)
        Each surface once (``g`` and ``-g`` are one), in the order found.
    """
    seen_nodes, seen, out = set(), set(), []
    for expr in exprs:
        for node in sp.preorder_traversal(sp.sympify(expr)):
            if node in seen_nodes or not isinstance(node, _SWITCH_TYPES):
                continue
            seen_nodes.add(node)
            for g in _surfaces(node):
                if not (g.free_symbols & varying) or g in seen or -g in seen:
                    continue
                seen.add(g)
                out.append((g, node))
    return out


def kinks(exprs, point, *, rtol: float = 1e-9) -> list[Kink]:
    """The switches of `exprs` that sit on their switching surface at `point`.

    Parameters
    ----------
    exprs : iterable of sympy.Expr
    point : mapping sympy.Symbol -> float
        A value for every free symbol.
    rtol : float
        A surface ``g = a - b`` counts as reached when
        ``|a - b| <= rtol * max(1, |a|, |b|)``.

    Returns
    -------
    list of Kink
        Each switch once, in the order found.
    """
    seen, found = set(), []
    for expr in exprs:
        for node in sp.preorder_traversal(sp.sympify(expr)):
            if node in seen or not isinstance(node, (sp.sign, sp.Abs, sp.Heaviside, sp.Max, sp.Min,
                                                     sp.floor, sp.ceiling, sp.Piecewise)):
                continue
            seen.add(node)
            for g in _surfaces(node):
                if not g.free_symbols:
                    continue
                parts = g.args if isinstance(g, sp.Add) else (g,)
                try:
                    value = complex(g.xreplace(point))
                    scale = max([1.0] + [abs(complex(a.xreplace(point))) for a in parts])
                except (TypeError, ValueError):
                    continue
                if value == value and abs(value) <= rtol * scale:
                    found.append(Kink(str(node)[:120], frozenset(g.free_symbols)))
                    break
    return found
