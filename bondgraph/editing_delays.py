"""Delaying an input, and realising delays as states for a model that cannot delay a signal.

:meth:`~bondgraph.editing.GraphEditing.delay_input` makes every element that reads an input
``u`` read ``u(t - T)`` instead: a delayed input (:class:`~bondgraph.elements.base.InputDelay`)
that the simulators realise exactly on the recorded samples
(:mod:`bondgraph.numerics.input_delays`).  An FMU has no delay primitive, so
:meth:`~bondgraph.editing.GraphEditing.with_delays_realised` replaces each delayed input by the
strictly proper Pade [2/3] approximant of :math:`e^{-sT}`,

.. math:: \\frac{1 - \\tfrac25 sT + \\tfrac1{20}(sT)^2}
                {1 + \\tfrac35 sT + \\tfrac3{20}(sT)^2 + \\tfrac1{60}(sT)^3},

three states in controllable canonical form owned by the element reading the delayed input:
error :math:`O((sT)^6)`, and a step goes through without a jump at t = 0 (strictly proper).
"""
from __future__ import annotations

from .editing_inputs import mentions, route_input
from .errors import GraphError, UnknownNameError
from .params import Param

__all__ = ["delay_input", "with_delays_realised", "pade_states"]


def delay_input(graph, u: str, time: str, value: float, *, before: float | Param | None = None,
                name: str | None = None):
    """A copy of `graph` whose elements read input `u` late by parameter `time` (`value`, s);
    :meth:`~bondgraph.editing.GraphEditing.delay_input` documents the call."""
    decl = next((d for d in graph.inputs() if d.name == u), None)
    if decl is None:
        raise UnknownNameError("input", u, [d.name for d in graph.inputs()], model=graph.name)
    if decl.delay is not None:
        raise GraphError(f"input {u!r} is already input {decl.delay.source!r} delayed by {decl.delay.time!r}: "
                         "change that delay instead")
    name = name or f"{u}_late"
    taken = set(graph.names())
    named = (("delayed input", name), ("delay parameter", time))
    if isinstance(before, Param):
        if before.name == time:
            raise GraphError(f"input {u!r}: the delay and the value before the run are both named {time!r}")
        named += (("parameter of the value before the run", before.name),)
    for label, new_name in named:
        if new_name in taken:
            raise GraphError(f"model {graph.name!r} already has a name {new_name!r} for the {label}")
    new, _ = route_input(graph, u, name)
    new.add_parameter(Param(time, value, unit="s", description=f"transport delay of input {u}", min=0.0))
    if isinstance(before, Param):
        new.add_parameter(before)
    new.add_input(name, default=decl.default, unit=decl.unit, description=f"{u} delayed by {time}",
                  delay_of=u, delay=time, before=before.name if isinstance(before, Param) else before)
    return new


def pade_states(u: str, T: str, z: tuple[str, str, str]) -> tuple[str, dict]:
    """The Pade [2/3] realisation of ``u`` delayed by ``T`` (module docstring): the delayed signal's
    expression and the three states' rates, states named `z`."""
    z1, z2, z3 = z
    rates = {z1: z2, z2: z3, z3: f"60*({u} - {z1} - 3*{T}/5*{z2} - 3*{T}**2/20*{z3})/{T}**3"}
    return f"{z1} - 2*{T}/5*{z2} + {T}**2/20*{z3}", rates


def with_delays_realised(graph):
    """A copy of `graph` in which every delayed input is the Pade [2/3] approximant of its
    delay (module docstring), its three states starting at rest at the input's ``before`` (its
    parameter's value where a parameter holds it; the source's default without one: the states
    cannot know a run's first value)."""
    new = graph
    for decl in [d for d in graph.inputs() if d.delay is not None]:
        users = [o for o in new.outputs.values() if mentions(str(o.expression), decl.name)]
        if users:
            raise GraphError(f"output {users[0].name!r} reads the delayed input {decl.name!r} directly; a "
                             "Pade realisation feeds only elements: read the element's variable instead")
        source, T = decl.delay.source, decl.delay.time
        z = tuple(f"z{i}_{decl.name}" for i in (1, 2, 3))
        expression, rates = pade_states(source, T, z)
        unit = decl.unit
        new, _ = route_input(new, decl.name, expression, states=rates,
                             initial={z[0]: _value_before(new, decl),
                                      z[1]: 0.0, z[2]: 0.0},
                             units={z[0]: unit, z[1]: f"({unit})/s" if unit else "1/s",
                                    z[2]: f"({unit})/s^2" if unit else "1/s^2"})
        del new.extra_inputs[decl.name]
        new._changed()
    return new if new is not graph else graph.copy()


def _value_before(graph, decl) -> float:
    """The delayed input `decl`'s value before a run: its ``before`` (a number, or the value of the
    parameter it names), else its default."""
    before = decl.delay.before
    if isinstance(before, str):
        return float(graph.parameters()[before].value)
    return decl.default if before is None else before
