"""What the co-simulation master drives: ports, the Component protocol, Python blocks.

A component owns nothing of the master's data except two views into the
master's single signal buffer, handed over once per run by
:meth:`Component.bind`: ``u`` (its inputs) and ``y`` (its outputs), both
contiguous float64 arrays in port order.  The master writes ``u`` and reads
``y``; the component reads ``u`` and writes ``y`` in place.  No arrays are
built per step, so a component costs only its own work.

Call sequence in one run (``t_k = t0 + k * step``)::

    bind(u, y)
    start(t0)                   # u holds the inputs at t0
    for k in 0 .. n:
        output(t_k)             # y <- outputs at t_k, from the current u
        advance(t_k, step)      # k < n only; u held over [t_k, t_k + step]
    stop()                      # always, also after an error
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

from cosim.errors import CosimError, PortTypeError

__all__ = ["Port", "Component", "PythonBlock"]


@dataclass(frozen=True)
class Port:
    """One scalar input or output of a component (an immutable value).

    Parameters
    ----------
    name : str
        Port name, unique among the component's ports; the signal is called
        ``"component.port"``.
    unit : str, optional
        Unit, e.g. ``"N"``; ``""`` means unspecified (connects to any unit).
    description : str, optional
    start : float, optional
        Value before the first :meth:`Component.output` (outputs) or while
        unconnected (inputs), in `unit`.
    """

    name: str
    unit: str = ""
    description: str = ""
    start: float = 0.0


@runtime_checkable
class Component(Protocol):
    """A co-simulation component: an FMU slave, a controller, a signal source.

    Attributes
    ----------
    name : str
        Unique within a co-simulation, without ``"."``.
    inputs, outputs : tuple of Port
        In the order of ``u`` and ``y``.
    feedthrough : frozenset of (str, str)
        ``(input_name, output_name)`` pairs where the output at time t depends
        on that input at the same t (direct feedthrough).  The master orders
        components and detects algebraic loops from it.
    """

    name: str
    inputs: tuple
    outputs: tuple
    feedthrough: frozenset

    def bind(self, u: np.ndarray, y: np.ndarray) -> None:
        """Keep the views ``u`` (shape (n_inputs,)) and ``y`` (shape (n_outputs,)).

        Called once per run, before :meth:`start`; both are C-contiguous
        float64 views into the master's buffer, valid until :meth:`stop`.
        """

    def start(self, t0: float) -> None:
        """Instantiate and initialise at ``t0`` (s); ``u`` holds the inputs at ``t0``."""

    def output(self, t: float) -> None:
        """Write the outputs at ``t`` (s), given the current ``u``, into ``y`` in place."""

    def advance(self, t: float, dt: float) -> None:
        """Advance from ``t`` to ``t + dt`` (s) with ``u`` held constant."""

    def stop(self) -> None:
        """Release resources; safe to call twice and after a failed start."""


def _as_port(p) -> Port:
    if isinstance(p, Port):
        return p
    if isinstance(p, str):
        return Port(p)
    raise PortTypeError(f"a port must be a Port or a name (str); found {p!r}")


class PythonBlock:
    """Base class of components written in Python.

    A subclass implements :meth:`output` (write ``self.y`` from ``self.u`` and
    ``t``) and, if it has a state, :meth:`start` and :meth:`advance`.

    Parameters
    ----------
    name : str
    inputs, outputs : sequence of Port or str, optional
        A ``str`` is a port without unit, start 0.
    feedthrough : iterable of (str, str), optional
        ``(input, output)`` pairs with direct feedthrough.  Default: every
        pair (conservative: an output may depend on every input); pass
        ``()`` for a block whose outputs depend on its state only.

    Attributes
    ----------
    u, y : ndarray
        The views given by :meth:`bind` (empty arrays before).

    Examples
    --------
    >>> class Gain(PythonBlock):
    ...     def __init__(self, name, k):
    ...         super().__init__(name, inputs=["u"], outputs=["y"])
    ...         self.k = k
    ...     def output(self, t):
    ...         self.y[0] = self.k * self.u[0]
    >>> sorted(Gain("g", 2.0).feedthrough)
    [('u', 'y')]
    """

    def __init__(self, name: str, *, inputs=(), outputs=(), feedthrough=None):
        self.name = str(name)
        self.inputs = tuple(_as_port(p) for p in inputs)
        self.outputs = tuple(_as_port(p) for p in outputs)
        for kind, ports in (("input", self.inputs), ("output", self.outputs)):
            names = [p.name for p in ports]
            dup = sorted({n for n in names if names.count(n) > 1})
            if dup:
                raise CosimError(f"block {self.name!r}: {kind} name(s) {', '.join(dup)} repeated",
                                 ports=[f"{self.name}.{n}" for n in dup])
        ins, outs = [p.name for p in self.inputs], [p.name for p in self.outputs]
        if feedthrough is None:
            self.feedthrough = frozenset((i, o) for i in ins for o in outs)
        else:
            self.feedthrough = frozenset((str(i), str(o)) for i, o in feedthrough)
            for i, o in self.feedthrough:
                if i not in ins or o not in outs:
                    raise CosimError(f"block {self.name!r}: feedthrough pair ({i!r}, {o!r}) names "
                                     f"a missing port; inputs are {', '.join(ins) or '(none)'}, "
                                     f"outputs are {', '.join(outs) or '(none)'}")
        self.u = np.zeros(len(self.inputs))
        self.y = np.array([p.start for p in self.outputs], dtype=float)

    def bind(self, u: np.ndarray, y: np.ndarray) -> None:
        """Keep the master's views (see :meth:`Component.bind`)."""
        self.u, self.y = u, y

    def start(self, t0: float) -> None:
        """Initialise at ``t0`` (s); default: nothing."""

    def output(self, t: float) -> None:
        """Write ``self.y`` at ``t`` (s); subclasses must implement it."""
        raise NotImplementedError(f"{type(self).__name__}.output is not implemented")

    def advance(self, t: float, dt: float) -> None:
        """Advance the state from ``t`` to ``t + dt`` (s); default: nothing (no state)."""

    def stop(self) -> None:
        """Release resources; default: nothing."""

    def __repr__(self) -> str:
        ins = ", ".join(p.name for p in self.inputs)
        outs = ", ".join(p.name for p in self.outputs)
        return f"<{type(self).__name__} {self.name!r} ({ins}) -> ({outs})>"
