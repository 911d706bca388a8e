"""bondgraph.symbols.parse caches parsed expressions by (text, what its identifiers resolve to)."""
import pytest
import sympy as sp

from bondgraph.errors import ExpressionError
from bondgraph.symbols import parse, sym


def test_same_text_other_bindings_give_other_expressions():
    u, v = sym("u"), sym("v")
    a = parse("Min(Max(u, 0), 10)", {"u": u}, owner="test")
    b = parse("Min(Max(u, 0), 10)", {"u": v, "w": u}, owner="test")   # u bound to another symbol
    assert a == sp.Min(sp.Max(u, 0), 10)
    assert b == sp.Min(sp.Max(v, 0), 10)
    assert a.subs(u, 12) == 10 and b.subs(v, -3) == 0


def test_unrelated_names_share_the_parse_and_unknown_names_still_fail():
    u = sym("u")
    a = parse("2*u + 1", {"u": u}, owner="test")
    assert parse("2*u + 1", {"u": u, "extra": sym("extra")}, owner="test") is a
    with pytest.raises(ExpressionError, match="unknown name"):
        parse("2*u + 1", {"x": u}, owner="test")      # u no longer known
