"""Sources: Se, Sf (named inputs or given functions of time) and modulated MSe, MSf."""
from __future__ import annotations

import math
import numbers

import sympy as sp

from ..errors import ParameterError
from .base import EFFORT, FLOW, Contribution, Element, InputDecl, unit_of

__all__ = ["Se", "Sf", "MSe", "MSf"]


class _Source(Element):
    directions = {"": "out"}
    _role = EFFORT

    def __init__(self, name: str, value=None, *, input: str | None = None, unit: str | None = None,
                 domain: str = "generic", description: str = ""):
        """A source whose value is a named input.

        Parameters
        ----------
        name : str
            Element name.
        value : float, str or sympy.Expr, optional
            Default value of the input: a number, or a function of time ``t``
            (e.g. ``"0.1*sin(2*pi*t)"``).  ``None`` means 0.
        input : str, optional
            Input name (default: the element name).
        unit : str, optional
            Unit of the source value (default from `domain`).
        domain : str
            Energy domain, for the default unit.
        """
        super().__init__(name, description=description)
        if value is not None and not isinstance(value, (str, sp.Basic)):
            if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value):
                raise ParameterError(f"{self.kind} {name!r}: value {value!r} is not a finite number, "
                                     "nor an expression of t", name=name)
        self.input = input or name
        self.domain = domain
        self.unit = unit if unit is not None else unit_of(domain, "effort" if self._role == EFFORT else "flow")
        self.value = value

    def declared_inputs(self):
        if isinstance(self.value, (str, sp.Basic)):
            default, function = 0.0, self.value
        else:
            default, function = float(self.value or 0.0), None
        word = "effort" if self._role == EFFORT else "flow"
        return [InputDecl(self.input, self.unit, default, function,
                          self.description or f"{word} of source {self.name}", (self.name, "value"))]

    def fixed_roles(self):
        return {"": self._role}

    def contribute(self, ports, names):
        port = ports[""]
        u = names[self.input]
        if self._role == EFFORT:
            return Contribution(defs=[(port.e, u)])
        return Contribution(defs=[(port.f, port.sign * u)])

    def _spec(self):
        spec = {"domain": self.domain, "unit": self.unit}
        if self.input != self.name:
            spec["input"] = self.input
        if self.value is not None:
            numeric = isinstance(self.value, numbers.Real) and not isinstance(self.value, bool)
            spec["value"] = float(self.value) if numeric else str(self.value)
        return spec


class Se(_Source):
    """Effort source: ``e = u`` with `u` a named input (power flows out of it)."""

    kind = "Se"
    _role = EFFORT


class Sf(_Source):
    """Flow source: ``f = u`` with `u` a named input (power flows out of it)."""

    kind = "Sf"
    _role = FLOW


class _Modulated(Element):
    directions = {"": "out"}
    _role = EFFORT

    def __init__(self, name: str, expression, *, params=None, unit: str | None = None,
                 domain: str = "generic", locals=None, description: str = ""):
        """A source whose value is an expression of states, inputs, parameters,
        held variables, bond variables (``e_<bond>``, ``f_<bond>``) and ``t``.

        Parameters
        ----------
        expression : str or sympy.Expr
            The modulation law.
        params : mapping or list of Param, optional
            Parameters the expression uses that are not defined elsewhere.
        locals : mapping str -> expression, optional
            Named intermediate quantities, in evaluation order; each may use
            the graph's names and the earlier locals, and `expression` may use
            them all.  They appear as ``<element>.<name>`` in the equations'
            ordered assignments (:attr:`StateEquations.assignments`).
        """
        from .base import param_dict
        super().__init__(name, description=description)
        self.expression = expression
        self.params = param_dict(params, f"{self.kind} {name!r}")
        self.domain = domain
        self.unit = unit if unit is not None else unit_of(domain, "effort" if self._role == EFFORT else "flow")
        self._set_locals(locals)

    def parameters(self):
        return list(self.params.values())

    def fixed_roles(self):
        return {"": self._role}

    def prepare(self, names):
        self._value = self._expr(self.expression, self._parse_locals(names), "modulation")

    def contribute(self, ports, names):
        port = ports[""]
        value = self._value
        if self._role == EFFORT:
            return Contribution(defs=[(port.e, value)], locals=list(self._local_defs))
        return Contribution(defs=[(port.f, port.sign * value)], locals=list(self._local_defs))

    def _spec(self):
        spec = {"expression": str(self.expression), "domain": self.domain, "unit": self.unit}
        if self.params:
            spec["params"] = {k: p.to_dict() for k, p in self.params.items()}
        if self.locals:
            spec["locals"] = {k: str(v) for k, v in self.locals.items()}
        return spec


class MSe(_Modulated):
    """Modulated effort source: ``e = expression``."""

    kind = "MSe"
    _role = EFFORT


class MSf(_Modulated):
    """Modulated flow source: ``f = expression``."""

    kind = "MSf"
    _role = FLOW
