"""Ordered causal assignments: the readable form of derived state equations.

The derivation (:mod:`bondgraph.equations`) defines every bond variable and
every element local by one short expression of others (the causal
assignments), then substitutes them into the state equations.  The
substituted right-hand sides of a model with switched laws repeat the same
subexpression many times (the PAM joint's valve table eight times per
state).  This module keeps the assignments instead, as modelling tools
such as 20-sim and Modelica compilers show them: named intermediate
variables in evaluation order, then state equations in terms of them.

Which intermediates get a name:

* every element local (``valve1.alpha``, ``muscle1.V``; see the ``locals``
  argument of :class:`~bondgraph.elements.EquationElement` and the modulated
  sources) -- the modeller asked for it;
* a bond variable whose definition is not trivial (not a symbol, a number
  or a negated symbol) and either is used twice or more, or has at least
  :data:`KEEP_OPS` operations.  It is shown under the element's own name
  when it is the effort or flow of a one-port element (``f_m1`` rather than
  ``f_bond3``);
* every other bond variable is substituted into the expressions that use it.

Variables of algebraic loops and of eliminated dependent storage keep their
solved (substituted) expression.  Substituting the assignments in order into
the short right-hand sides gives back exactly the flat ``f``, ``h`` and
``held_update`` (tested symbolically and numerically).
"""
from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

__all__ = ["Readable", "readable_form", "substitute", "needed_assignments", "KEEP_OPS"]

#: Operations above which a bond variable used once still gets its own line.
KEEP_OPS = 8


@dataclass(frozen=True)
class Readable:
    """Assignments and the short expressions that use them (all sympy)."""

    assignments: tuple
    f: tuple
    h: tuple
    held_update: tuple


def _trivial(expr: sp.Expr) -> bool:
    if expr.is_Atom:
        return True
    return isinstance(expr, sp.Mul) and len(expr.args) == 2 and expr.args[0] == -1 and expr.args[1].is_Atom


def _aliases(names) -> dict:
    """Bond symbol -> (element-named symbol, sign) for one-port elements' e_/f_ names."""
    out = {}
    for key, value in names.items():
        if not (key.startswith("e_") or key.startswith("f_")):
            continue
        if isinstance(value, sp.Symbol) and value.name != key:
            out.setdefault(value, (sp.Symbol(key, real=True), 1))
        elif isinstance(value, sp.Mul) and value.args[0] == -1 and isinstance(value.args[1], sp.Symbol):
            out.setdefault(value.args[1], (sp.Symbol(key, real=True), -1))
    return out


def readable_form(defs, order, locals_, final, names, rates, outputs, updates) -> Readable:
    """Build the ordered assignments (see the module docstring).

    Parameters
    ----------
    defs : dict Symbol -> Expr
        Each variable's causal definition (bond variables and element locals).
    order : list of Symbol
        The variables in an evaluation order (dependencies first).
    locals_ : set of Symbol
        Element locals (always named).
    final : dict Symbol -> Expr
        Variables whose definition is replaced by their solved, substituted
        expression (algebraic-loop members, dependent-storage efforts/flows).
    names : mapping str -> Basic
        The graph's name table (for element-named aliases of bond variables).
    rates, outputs, updates : list of Expr
        State rates, output expressions and held updates over the variables.
    """
    uses: dict = {}
    for var in order:
        body = final.get(var, defs[var])
        for s in body.free_symbols:
            if s in defs:
                uses[s] = uses.get(s, 0) + 1
    for expr in (*rates, *outputs, *updates):
        for s in expr.free_symbols:
            if s in defs:
                uses[s] = uses.get(s, 0) + 1
    aliases = _aliases(names)
    ref: dict = {}          # variable -> what expressions that use it contain
    kept: list = []         # (display symbol, body)
    for var in order:
        body = final.get(var)
        if body is None:
            body = defs[var]
            deps = {s: ref[s] for s in body.free_symbols if s in ref}
            body = body.xreplace(deps) if deps else body
        keep = var in locals_ or (not _trivial(body) and (uses.get(var, 0) >= 2 or sp.count_ops(body) >= KEEP_OPS))
        if not keep:
            ref[var] = body
            continue
        shown, sign = aliases.get(var, (var, 1))
        kept.append((shown, body if sign > 0 else -body))
        ref[var] = shown if sign > 0 else -shown

    def short(expr):
        deps = {s: ref[s] for s in expr.free_symbols if s in ref}
        return expr.xreplace(deps) if deps else expr

    f, h, upd = [short(e) for e in rates], [short(e) for e in outputs], [short(e) for e in updates]
    kept = needed_assignments(kept, (*f, *h, *upd))   # drop assignments nothing uses
    return Readable(_grouped(kept), tuple(f), tuple(h), tuple(upd))


def needed_assignments(assignments, exprs) -> list:
    """The ``(symbol, body)`` pairs of `assignments` that `exprs` use, directly or through
    other assignments, in their given order (a walk back from the expressions)."""
    bodies = dict(assignments)
    needed, stack = set(), [s for e in exprs for s in sp.sympify(e).free_symbols if s in bodies]
    while stack:
        s = stack.pop()
        if s not in needed:
            needed.add(s)
            stack += [d for d in bodies[s].free_symbols if d in bodies]
    return [(s, e) for s, e in assignments if s in needed]


def _grouped(kept: list) -> tuple:
    """`kept` in an evaluation order that lists one element's locals together
    (groups in order of first appearance; dependencies still first)."""
    import networkx as nx

    def owner(s):
        name = s.name.partition(".")[0] if "." in s.name else s.name[2:] if s.name[:2] in ("e_", "f_") else s.name
        return name

    index = {s: i for i, (s, _) in enumerate(kept)}
    first: dict = {}
    for s, _ in kept:
        first.setdefault(owner(s), index[s])
    graph = nx.DiGraph()
    graph.add_nodes_from(index)
    graph.add_edges_from((d, s) for s, e in kept for d in e.free_symbols if d in index)
    bodies = dict(kept)
    order = nx.lexicographical_topological_sort(
        graph, key=lambda s: (first[owner(s)], index[s]))
    return tuple((s, bodies[s]) for s in order)


def substitute(assignments, expr: sp.Expr) -> sp.Expr:
    """`expr` with the `assignments` substituted (last first), i.e. the flat form."""
    for symbol, body in reversed(assignments):
        if expr.has(symbol):
            expr = expr.xreplace({symbol: body})
    return expr

