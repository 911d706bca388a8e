"""Actuator (input) and sensor (output) kinds.

The recorded input ``u`` stays the model's input; the elements that used it
see an effective input instead (:func:`~diagnosis.catalogue_common.route_input`):

* ``valve_lag``: :math:`\\tau \\dot x = u - x`, effective input :math:`x` (an extra
  state).  Added states start where the input was before the experiment
  (:func:`resting_input`: the value at which the nominal initial state is at
  rest, usually 0), so the first command step goes through the lag too.
* ``transport_delay``: :math:`u(t - T)`, realised as the strictly proper Padé
  [2/3] approximant of :math:`e^{-sT}`,

  .. math:: \\frac{1 - \\tfrac25 sT + \\tfrac1{20}(sT)^2}
                  {1 + \\tfrac35 sT + \\tfrac3{20}(sT)^2 + \\tfrac1{60}(sT)^3},

  in controllable canonical form: three states owned by the element that
  reads ``u``, with :math:`T` a parameter.  FMI has no delay primitive, and a
  Padé chain is ordinary states, so the graph exports (Model Exchange and
  Co-Simulation) like any other.  Error :math:`O((sT)^6)`; a step is
  reproduced without a jump at t = 0 (strictly proper).
* ``saturation``: :math:`\\min(\\max(u, u_{min}), u_{max})`.

Sensor kinds transform the model output ``y`` before it is compared:
``sensor_offset``: :math:`y + \\delta`; ``sensor_gain``: :math:`g\\, y`;
``saturation`` (the sensor's range): :math:`\\min(\\max(y, y_{min}), y_{max})`.
"""
from __future__ import annotations

import numpy as np

from .errors import BondcosimError

from .catalogue_common import ParamSpec, fresh_name, route_input

__all__ = ["INPUT_KINDS", "OUTPUT_KINDS", "make_input", "make_output", "build_signal", "explain_signal"]

INPUT_KINDS = ("valve_lag", "transport_delay", "saturation")
OUTPUT_KINDS = ("saturation", "sensor_offset", "sensor_gain")


def make_input(graph, place, span: float, dt: float, recorded, taken) -> list[dict]:
    """Prototypes for an input place (`recorded`: the recorded input in model units, or None)."""
    u = place.name
    decl = next(d for d in graph.inputs() if d.name == u)
    unit = decl.unit
    values = np.asarray(recorded, dtype=float) if recorded is not None else np.array([decl.default - 1.0,
                                                                                       decl.default + 1.0])
    u0 = resting_input(graph, u, recorded)
    lo, hi = float(np.min(values)), float(np.max(values))
    width = max(hi - lo, 1e-12)
    q_lo, q_hi = (float(v) for v in np.percentile(values, [5, 95]))
    mid = float(np.median(values))
    q_lo, q_hi = min(q_lo, mid - 1e-3 * width), max(q_hi, mid + 1e-3 * width)
    tau, delay = fresh_name(taken, f"tau_lag_{u}"), fresh_name(taken, f"T_delay_{u}")
    times = [k * dt for k in (0.5, 2, 8, 32) if k * dt < span / 4]
    u_min, u_max = fresh_name(taken, f"u_min_{u}"), fresh_name(taken, f"u_max_{u}")
    limits = [(float(np.quantile(values, q)), float(np.quantile(values, 1 - q))) for q in (0.02, 0.1, 0.25)]
    limits = [(a, b) for a, b in limits if a < mid < b]
    # one-sided starts first: on a tie (no sample beyond a limit) the limit stays inactive
    sat_starts = [{u_min: lo - 1e-3 * width, u_max: b} for _, b in limits]
    sat_starts += [{u_min: a, u_max: hi + 1e-3 * width} for a, _ in limits]
    sat_starts += [{u_min: a, u_max: b} for a, b in limits]
    return [
        dict(kind="valve_lag", initial={f"x_lag_{u}": u0}, starts=[{tau: v} for v in times], params=[
            ParamSpec(tau, max(5 * dt, span / 100), dt / 20, span / 2, "s",
                      f"time constant of the actuator lag on {u}")]),
        dict(kind="transport_delay", initial={f"z1_delay_{u}": u0}, starts=[{delay: v} for v in times], params=[
            ParamSpec(delay, max(3 * dt, span / 200), dt / 20, span / 4, "s", f"transport delay of {u}")]),
        dict(kind="saturation", starts=sat_starts, params=[
            # a recording of a saturated input has many samples AT the limit: its median may be
            # the limit itself, so each limit may range over the whole recorded span
            ParamSpec(u_min, q_lo, lo - width, hi, unit, f"lower saturation of {u}"),
            ParamSpec(u_max, q_hi, lo, hi + width, unit, f"upper saturation of {u}")]),
    ]


def resting_input(graph, u: str, recorded) -> float:
    """The value of input `u` before the experiment.

    Of 0, the input's default and its first recorded value, the one at which the
    nominal initial state is closest to rest: the rates :math:`|f_i(x_0, u)|` (other
    inputs at their defaults) are normalised per state by their largest value over
    the three, summed, and the smallest sum wins (ties: in that order).  The first
    recorded value when the model cannot be evaluated, or when the rates do not depend
    on the input at all (nothing says where it rested: the actuator is taken to have
    followed its first command).
    """
    from bondgraph.numerics.evaluate import compile_model
    decl = next(d for d in graph.inputs() if d.name == u)
    first = float(recorded[0]) if recorded is not None else float(decl.default)
    options = (0.0, float(decl.default), first)
    try:
        eqs = graph.equations()
        model = compile_model(eqs, backend="numpy")
        base = np.array([float(eqs.input_defaults.get(n, 0.0)) for n in model.input_names])
        trials = np.tile(base, (len(options), 1))
        trials[:, list(model.input_names).index(u)] = options
        x0 = np.tile(model.default_state, (len(options), 1))
        rates = np.abs(np.asarray(model.f(x0, trials), dtype=float)).reshape(len(options), -1)
    except (BondcosimError, ValueError, TypeError):
        return first
    if not np.isfinite(rates).all():
        return first
    peak = rates.max(axis=0)
    score = (rates[:, peak > 0] / peak[peak > 0]).sum(axis=1)
    if np.allclose(rates, rates[0], rtol=1e-12, atol=0.0):
        return first
    return options[int(np.argmin(score))]


def make_output(graph, place, measured, taken) -> list[dict]:
    """Prototypes for an output place (`measured`: the recorded output in model units, or None)."""
    y = place.name
    unit = graph.outputs[y].unit
    width = float(np.ptp(measured)) if measured is not None and np.ptp(measured) > 0 else 1.0
    values = np.asarray(measured, dtype=float) if measured is not None else np.array([-1.0, 1.0])
    lo, hi = float(np.min(values)), float(np.max(values))
    y_min, y_max = fresh_name(taken, f"y_min_{y}"), fresh_name(taken, f"y_max_{y}")
    # a clipped sensor reads its limit on many samples: start each side at the recorded extreme
    # (inactive) and at a little inside it, one side at a time
    starts = [{y_min: lo - 1e-3 * width, y_max: hi - f * width} for f in (0.0, 0.05)]
    starts += [{y_min: lo + f * width, y_max: hi + 1e-3 * width} for f in (0.0, 0.05)]
    return [
        dict(kind="saturation", starts=starts, params=[
            ParamSpec(y_min, lo - 1e-3 * width, lo - width, hi, unit, f"lower end of the {y} sensor's range"),
            ParamSpec(y_max, hi + 1e-3 * width, lo, hi + width, unit, f"upper end of the {y} sensor's range")]),
        dict(kind="sensor_offset", params=[ParamSpec(fresh_name(taken, f"offset_{y}"), 0.0, -2 * width, 2 * width,
                                                     unit, f"offset of the {y} sensor")]),
        dict(kind="sensor_gain", params=[ParamSpec(fresh_name(taken, f"gain_{y}"), 1.0, 0.2, 5.0, "1",
                                                   f"gain of the {y} sensor")]),
    ]


def build_signal(data: dict, graph, cand, values: dict) -> None:
    """Transform the input or output of `cand` in the graph dict `data`."""
    name = cand.place.name
    p = [spec.name for spec in cand.params]
    if cand.place.kind == "output":
        entry = next(o for o in data["outputs"] if o["name"] == name)
        expr = entry["expression"]
        if cand.kind == "sensor_offset":
            entry["expression"] = f"({expr}) + {p[0]}"
        elif cand.kind == "sensor_gain":
            entry["expression"] = f"{p[0]}*({expr})"
        else:
            entry["expression"] = f"Min(Max({expr}, {p[0]}), {p[1]})"
        return
    unit = next(d.unit for d in graph.inputs() if d.name == name)
    if cand.kind == "saturation":
        route_input(data, graph, name, f"Min(Max({name}, {p[0]}), {p[1]})")
    elif cand.kind == "valve_lag":
        x = f"x_lag_{name}"
        route_input(data, graph, name, x, states={x: f"({name} - {x})/{p[0]}"}, initial=dict(cand.initial),
                    units={x: unit})
    else:  # transport_delay: Pade [2/3], controllable canonical form
        z1, z2, z3, T = f"z1_delay_{name}", f"z2_delay_{name}", f"z3_delay_{name}", p[0]
        states = {z1: z2, z2: z3,
                  z3: f"60*({name} - {z1} - 3*{T}/5*{z2} - 3*{T}**2/20*{z3})/{T}**3"}
        route_input(data, graph, name, f"{z1} - 2*{T}/5*{z2} + {T}**2/20*{z3}", states=states,
                    initial={z1: cand.initial.get(z1, 0.0), z2: 0.0, z3: 0.0},
                    units={z1: unit, z2: f"({unit})/s", z3: f"({unit})/s^2"})


def explain_signal(cand, values: dict, show) -> str:
    """Plain-language sentence for an input or output candidate."""
    name = cand.place.name
    p = [spec.name for spec in cand.params]
    if cand.kind == "valve_lag":
        return (f"the actuator driven by {name} follows its command with a lag of {show(p[0])}: "
                f"a first-order valve/actuator lag on input {name}")
    if cand.kind == "transport_delay":
        return (f"the input {name} acts {show(p[0])} late: a transport delay on input {name} "
                "(Pade [2/3] states in the model)")
    if cand.kind == "saturation" and cand.place.kind == "output":
        return (f"the {name} sensor reads nothing beyond {show(p[0])} .. {show(p[1])}: "
                f"the range of the {name} sensor (saturation of output {name})")
    if cand.kind == "saturation":
        return (f"the input {name} has no effect beyond {show(p[0])} .. {show(p[1])}: "
                f"saturation of input {name}")
    if cand.kind == "sensor_offset":
        return f"the {name} sensor reads {show(p[0])} off: a sensor offset on output {name}"
    return f"the {name} sensor reads {show(p[0])} times the true value: a sensor gain error on output {name}"
