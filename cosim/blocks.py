"""Python blocks for co-simulation: signal sources and a discrete PI controller.

Every block has one output (default name ``"y"``, ``"u"`` for :class:`PI`)
whose unit you choose.  Times are compared with a tolerance of
``1e-12 * max(1, |t|)`` s, so a step or table breakpoint on the
communication grid ``t0 + k * step`` takes effect at that point even when the
product rounds a hair below it.
"""
from __future__ import annotations

import math

import numpy as np

from cosim.errors import CosimError

from .component import Port, PythonBlock

__all__ = ["Constant", "Step", "Function", "Table", "PI", "Antagonistic"]


def _tol(t: float) -> float:
    return 1e-12 * max(1.0, abs(t))


def _finite(block: str, what: str, value) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise CosimError(f"block {block!r}: {what} must be a number; found {value!r}") from None
    if not math.isfinite(v):
        raise CosimError(f"block {block!r}: {what} must be finite; found {v}")
    return v


class Constant(PythonBlock):
    """Constant output ``y = value``.

    Parameters
    ----------
    name : str
    value : float
        In `unit`.
    unit : str, optional
    output : str, optional
        Output port name.
    """

    def __init__(self, name: str, value: float, unit: str = "", *, output: str = "y"):
        self.value = _finite(name, "value", value)
        super().__init__(name, outputs=[Port(output, unit, "constant", self.value)])

    def output(self, t: float) -> None:
        self.y[0] = self.value


class Step(PythonBlock):
    """Step: ``y = before`` for ``t < t_step``, ``y = after`` from ``t_step`` on.

    Parameters
    ----------
    name : str
    t_step : float, s
    before, after : float, optional
        Values in `unit` (default 0 and 1).
    unit : str, optional
    output : str, optional
    """

    def __init__(self, name: str, t_step: float, before: float = 0.0, after: float = 1.0,
                 unit: str = "", *, output: str = "y"):
        self.t_step = _finite(name, "t_step", t_step)
        self.before = _finite(name, "before", before)
        self.after = _finite(name, "after", after)
        super().__init__(name, outputs=[Port(output, unit, "step", self.before)])

    def output(self, t: float) -> None:
        self.y[0] = self.after if t >= self.t_step - _tol(self.t_step) else self.before


class Function(PythonBlock):
    """Output given by a Python function of time, ``y = fn_of_t(t)``.

    Parameters
    ----------
    name : str
    fn_of_t : callable float -> float
        Time (s) to value (in `unit`).
    unit : str, optional
    output : str, optional
    """

    def __init__(self, name: str, fn_of_t, unit: str = "", *, output: str = "y"):
        if not callable(fn_of_t):
            raise CosimError(f"block {name!r}: fn_of_t must be callable; found {fn_of_t!r}")
        self.fn = fn_of_t
        super().__init__(name, outputs=[Port(output, unit, "function of time")])

    def output(self, t: float) -> None:
        self.y[0] = self.fn(t)


class Table(PythonBlock):
    """Output from a time table, held or linearly interpolated.

    Before the first time the output is ``values[0]``, after the last
    ``values[-1]``.

    Parameters
    ----------
    name : str
    times : array_like, shape (n,), s
        Strictly increasing.
    values : array_like, shape (n,)
        In `unit`.
    unit : str, optional
    interpolation : {"linear", "hold"}, optional
        ``"hold"``: zero-order hold, the value of the last time <= t.
    output : str, optional
    """

    def __init__(self, name: str, times, values, unit: str = "", *,
                 interpolation: str = "linear", output: str = "y"):
        times = np.asarray(times, dtype=float).reshape(-1)
        values = np.asarray(values, dtype=float).reshape(-1)
        if times.size == 0 or times.shape != values.shape:
            raise CosimError(f"block {name!r}: times and values must be non-empty and of equal "
                             f"length; found {times.size} times and {values.size} values")
        if not (np.all(np.isfinite(times)) and np.all(np.isfinite(values))):
            raise CosimError(f"block {name!r}: times and values must be finite")
        if np.any(np.diff(times) <= 0):
            raise CosimError(f"block {name!r}: times must be strictly increasing")
        if interpolation not in ("linear", "hold"):
            raise CosimError(f"block {name!r}: interpolation must be 'linear' or 'hold'; "
                             f"found {interpolation!r}")
        self.times, self.values, self.interpolation = times, values, interpolation
        super().__init__(name, outputs=[Port(output, unit, f"table ({interpolation})",
                                             float(values[0]))])

    def output(self, t: float) -> None:
        if self.interpolation == "linear":
            self.y[0] = np.interp(t, self.times, self.values)
        else:
            i = int(np.searchsorted(self.times, t + _tol(t), side="right")) - 1
            self.y[0] = self.values[max(i, 0)]


class PI(PythonBlock):
    r"""Discrete PI controller with output limits and anti-windup.

    At each communication point :math:`t_k` (inputs: setpoint :math:`r`,
    measurement :math:`y_m`):

    .. math::

        e_k = r_k - y_{m,k}, \qquad
        u_k = \mathrm{sat}_{[u_{min}, u_{max}]}\left(k_p e_k + k_i I_k\right), \\
        I_{k+1} = I_k + \Delta t\, e_k
        \quad\text{unless } u_k \text{ is saturated and } e_k \text{ pushes further into the limit}

    (forward Euler with the error held over the step; the clamping form of
    anti-windup: the integral stops while saturated at ``u_max`` with
    :math:`k_i e > 0` or at ``u_min`` with :math:`k_i e < 0`, so it can
    always unwind).
    Both inputs feed through to the output.

    Parameters
    ----------
    name : str
    kp : float
        Proportional gain, output unit per input unit.
    ki : float
        Integral gain, output unit per (input unit s).
    u_min, u_max : float, optional
        Output limits (default unlimited).
    unit_in, unit_out : str, optional
        Units of the inputs and of the output.
    integral0 : float, optional
        :math:`I_0`, input unit s.
    setpoint, measurement, output : str, optional
        Port names (default ``"r"``, ``"y_m"``, ``"u"``).

    Attributes
    ----------
    integral : float
        :math:`I_k`, input unit s.
    """

    def __init__(self, name: str, kp: float, ki: float, *, u_min: float = -math.inf,
                 u_max: float = math.inf, unit_in: str = "", unit_out: str = "",
                 integral0: float = 0.0, setpoint: str = "r", measurement: str = "y_m",
                 output: str = "u"):
        self.kp, self.ki = _finite(name, "kp", kp), _finite(name, "ki", ki)
        self.u_min, self.u_max = float(u_min), float(u_max)
        if math.isnan(self.u_min) or math.isnan(self.u_max) or not self.u_min < self.u_max:
            raise CosimError(f"block {name!r}: need u_min < u_max; found {u_min}, {u_max}")
        self.integral0 = _finite(name, "integral0", integral0)
        self.integral = self.integral0
        super().__init__(name, inputs=[Port(setpoint, unit_in, "setpoint"),
                                       Port(measurement, unit_in, "measurement")],
                         outputs=[Port(output, unit_out, "controller output")])

    def start(self, t0: float) -> None:
        self.integral = self.integral0

    def _law(self):
        e = self.u[0] - self.u[1]
        v = self.kp * e + self.ki * self.integral
        return e, v

    def output(self, t: float) -> None:
        _, v = self._law()
        self.y[0] = min(max(v, self.u_min), self.u_max)

    def advance(self, t: float, dt: float) -> None:
        e, v = self._law()
        if (v > self.u_max and self.ki * e > 0.0) or (v < self.u_min and self.ki * e < 0.0):
            return   # anti-windup: saturated and e would push further in
        self.integral += dt * e


class Antagonistic(PythonBlock):
    """Split one command into an antagonistic pair: ``a = u0 + v``, ``b = u0 - v``.

    For actuators that work in pairs (the two valves of a PAM joint, the two
    tendons of a cable drive).  ``v`` feeds through to both outputs.

    Parameters
    ----------
    name : str
    u0 : float
        Common command, output unit (e.g. 5 V: both valves half open).
    unit : str, optional
        Unit of input and outputs.
    outputs : (str, str), optional
        Output port names (default ``"u1"``, ``"u2"``).
    """

    def __init__(self, name: str, u0: float, *, unit: str = "", outputs=("u1", "u2")):
        self.u0 = _finite(name, "u0", u0)
        super().__init__(name, inputs=[Port("v", unit, "differential command")],
                         outputs=[Port(outputs[0], unit, "u0 + v", start=self.u0),
                                  Port(outputs[1], unit, "u0 - v", start=self.u0)])

    def output(self, t: float) -> None:
        self.y[0] = self.u0 + self.u[0]
        self.y[1] = self.u0 - self.u[0]
