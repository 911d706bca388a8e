"""Symbols and the parsing of user expressions.

All symbols of a model are real sympy Symbols created here, so that a name
always maps to the same symbol.  User expressions (strings) are parsed
against an explicit table of names; a name the table does not hold is an
:class:`~bondgraph.errors.ExpressionError` that names it, never a silently
created free symbol.
"""
from __future__ import annotations

import re
import tokenize
from typing import Mapping

import sympy as sp
from sympy.parsing.sympy_parser import (
    convert_xor,
    parse_expr,
    standard_transformations,
)

from .errors import ExpressionError

__all__ = ["sym", "parse", "as_expression", "FUNCTIONS", "TIME", "STEP"]

#: Functions a user expression may call, by name.
FUNCTIONS: dict[str, object] = {
    name: getattr(sp, name)
    for name in (
        "sin", "cos", "tan", "asin", "acos", "atan", "atan2", "sinh", "cosh", "tanh",
        "exp", "log", "sqrt", "Abs", "sign", "Max", "Min", "Piecewise", "Heaviside",
        "pi", "E", "floor", "ceiling",
    )
}
FUNCTIONS["abs"] = sp.Abs
FUNCTIONS["min"] = sp.Min
FUNCTIONS["max"] = sp.Max

# Names parse_expr's generated code needs in its namespace.
_PARSER_NAMESPACE = {
    "Integer": sp.Integer, "Float": sp.Float, "Rational": sp.Rational,
    "Symbol": sp.Symbol, "Function": sp.Function,
}
_TRANSFORMS = standard_transformations + (convert_xor,)
#: parsed expressions by (text, what its identifiers resolve to): sympy expressions are immutable, and parsing nested
#: Min/Max (the pam valve law) takes about 1 s, once per graph derivation without this
_PARSED: dict = {}


def sym(name: str) -> sp.Symbol:
    """The model symbol called `name` (real-valued)."""
    return sp.Symbol(name, real=True)


#: Time, s.
TIME = sym("t")
#: Integration sub-step of held-variable updates, s.
STEP = sym("h_step")


def parse(text: str, names: Mapping[str, sp.Basic], *, owner: str) -> sp.Expr:
    """Parse a user expression against a table of known names.

    Parameters
    ----------
    text : str
        Expression in Python/sympy syntax (``^`` is accepted for powers).
    names : mapping str -> sympy object
        Every name the expression may use besides :data:`FUNCTIONS`.
    owner : str
        What the expression belongs to, for error messages.

    Returns
    -------
    sympy.Expr

    Raises
    ------
    ExpressionError
        When the text does not parse, or uses names not in `names`.
    """
    if not isinstance(text, str) or not text.strip():
        raise ExpressionError(f"{owner}: expected a non-empty expression, got {text!r}",
                              owner=owner, expression=str(text))
    try:   # the result depends only on what the text's identifiers resolve to
        key = (text, tuple((w, names.get(w)) for w in sorted(set(re.findall(r"[A-Za-z_]\w*", text)))))
        hash(key)
    except TypeError:   # an unhashable entry: parse without the cache
        key = None
    if key is not None and key in _PARSED:
        return _PARSED[key]
    namespace = dict(_PARSER_NAMESPACE)
    namespace.update(FUNCTIONS)
    try:
        expr = parse_expr(text, local_dict=dict(names), global_dict=namespace,
                          transformations=_TRANSFORMS, evaluate=True)
    except (SyntaxError, TypeError, ValueError, AttributeError, NameError,
            tokenize.TokenError, sp.SympifyError) as exc:
        raise ExpressionError(f"{owner}: cannot parse expression {text!r} ({exc.__class__.__name__}: {exc})",
                              owner=owner, expression=text) from None
    if not isinstance(expr, sp.Expr):
        raise ExpressionError(f"{owner}: {text!r} is not an arithmetic expression",
                              owner=owner, expression=text)
    known = set()
    for value in names.values():
        known.update(value.free_symbols if isinstance(value, sp.Basic) else ())
    unknown = sorted(str(s) for s in expr.free_symbols if s not in known)
    undefined_functions = sorted(str(fn.func) for fn in expr.atoms(sp.core.function.AppliedUndef))
    if unknown or undefined_functions:
        bad = unknown + [f"{f}()" for f in undefined_functions]
        raise ExpressionError(
            f"{owner}: expression {text!r} uses unknown name(s) {', '.join(bad)}; "
            f"known names are {', '.join(sorted(names)) or '(none)'} and the functions "
            f"{', '.join(sorted(k for k in FUNCTIONS if k.islower()))}",
            owner=owner, expression=text, unknown=bad)
    if key is not None and len(_PARSED) < 4096:
        _PARSED[key] = expr
    return expr


def as_expression(value, names: Mapping[str, sp.Basic], *, owner: str) -> sp.Expr:
    """A number, sympy expression or string turned into an expression over `names`.

    Sympy expressions are re-bound by symbol *name* to the symbols of `names`,
    so an expression written with plain ``sympy.Symbol('m')`` works.
    """
    if isinstance(value, str):
        return parse(value, names, owner=owner)
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return sp.Float(value) if isinstance(value, float) else sp.Integer(value)
    if isinstance(value, sp.Basic):
        mapping = {}
        unknown = []
        for s in value.free_symbols:
            if s in names.values():
                continue
            if s.name in names:
                mapping[s] = names[s.name]
            else:
                unknown.append(s.name)
        if unknown:
            raise ExpressionError(
                f"{owner}: expression {value} uses unknown name(s) {', '.join(sorted(unknown))}; "
                f"known names are {', '.join(sorted(names))}",
                owner=owner, expression=str(value), unknown=sorted(unknown))
        return value.xreplace(mapping)
    raise ExpressionError(f"{owner}: expected a number, string or sympy expression, got {type(value).__name__}",
                          owner=owner, expression=repr(value))
