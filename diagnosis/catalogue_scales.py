"""Scales taken from the data, for the catalogue's guesses and bounds.

The nominal model is simulated once on the recorded inputs and the flows,
efforts and displacements at a place are read off it (as extra outputs of a
copy of the graph).  Without an experiment every scale is 1 in SI units, so a
catalogue can still be listed.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import BondcosimError

__all__ = ["command_hold", "Scales", "simulate_expressions", "rms", "pressure_variables"]


@dataclass(frozen=True)
class Scales:
    """Typical magnitudes at a place (SI units of the place).

    Attributes
    ----------
    flow : float
        RMS of the junction's common flow (1-junction) or of its largest bond flow (0-junction).
    effort : float
        RMS of the junction's largest bond effort (1-junction) or of its common effort (0-junction),
        or the spread of a measured output in its unit if larger.
    displacement : float
        RMS of the integrated flow about its mean.
    span : float, s
        Duration of the experiment.
    dt : float, s
        Median sample interval.
    from_data : bool
        False when no experiment was given (every scale 1).
    hold : float or None, s
        Median time the recorded inputs hold a level (:func:`command_hold`; None: no held levels
        to tell, such as smooth commands, or no experiment).
    """

    flow: float = 1.0
    effort: float = 1.0
    displacement: float = 1.0
    span: float = 1.0
    dt: float = 0.01
    from_data: bool = False
    hold: float | None = None


def rms(values) -> float:
    """Root mean square of `values` (0 for an empty array)."""
    values = np.asarray(values, dtype=float)
    return float(np.sqrt(np.mean(values ** 2))) if values.size else 0.0


def simulate_expressions(graph, experiment, expressions: dict, x0=None) -> dict:
    """Values of `expressions` along the nominal simulation of `experiment`.

    Parameters
    ----------
    graph : BondGraph
    experiment : Experiment
        Recorded inputs (model units, zero-order hold) and time, s.
    expressions : dict str -> str
        Label -> expression of states, inputs, parameters and bond variables.
    x0 : dict or array, optional
        The initial state (default the model's).

    Returns
    -------
    dict str -> ndarray
        Label -> values at the experiment's times; empty when
        the nominal model cannot be simulated (the caller falls back to unit scales).
    """
    from .residuals import OutputSimulator
    labels = {f"scale_{k}": label for k, label in enumerate(expressions)}
    try:
        g = graph.with_outputs({key: str(expressions[label]) for key, label in labels.items()})
        result = OutputSimulator(g, experiment, outputs=list(labels))(None, x0)
    except BondcosimError:
        return {}
    return {label: np.asarray(result[key], dtype=float) for key, label in labels.items()}


def command_hold(experiment) -> float | None:
    """Median time the experiment's recorded inputs hold a level between two changes, s; None
    where no input changes level at least three times (a smooth or constant command)."""
    t = np.asarray(experiment.t, dtype=float)
    holds = []
    for u in experiment.inputs.values():
        u = np.asarray(u, dtype=float)
        steps = np.flatnonzero(np.abs(np.diff(u)) > 1e-12 * max(float(np.max(np.abs(u))), 1e-300))
        if steps.size >= 3 and steps.size < 0.5 * u.size:       # held levels, not a smooth signal
            holds.extend(np.diff(t[steps + 1]))
    return float(np.median(holds)) if holds else None


def experiment_times(experiment) -> tuple[float, float]:
    """(span, median sample interval) of an experiment, s."""
    t = np.asarray(experiment.t, dtype=float)
    return float(t[-1] - t[0]), float(np.median(np.diff(t)))


def junction_scales(graph, junction: str, experiment, signals=None, x0=None, estimate=None) -> tuple[Scales, dict]:
    """Scales at a junction and the nominal values the catalogue needs there, from ONE simulation.

    `signals` (label -> expression, optional): further variables to read, keyed
    ``signal:<label>`` (the signals that may modulate a friction there); `x0` the state the
    simulation starts from (default the model's); `estimate` (optional, on the experiment's
    times) an extra effort (1-junction) or flow (0-junction) the simulation adds at the junction:
    the located correction, which keeps the run on the recording where the nominal's own drifts
    (a force-driven carriage whose mass is off drifts one way, and its flow there never reverses).

    Returns
    -------
    (Scales, dict str -> ndarray)
        The values are keyed ``e_<bond>`` / ``f_<bond>`` for the junction's bonds,
        ``pressure:<label>`` for :func:`pressure_variables`, ``state:<name>`` for
        the states of the C and I elements on the junction and ``signal:<label>`` for
        `signals` (empty without an experiment).
    """
    if experiment is None:
        return Scales(), {}
    span, dt = experiment_times(experiment)
    bonds = [b for b, _ in graph.bonds_of(junction)]
    exprs = {f"f_{b.name}": f"f_{b.name}" for b in bonds}
    exprs.update({f"e_{b.name}": f"e_{b.name}" for b in bonds})
    exprs.update({f"pressure:{label}": expr for label, expr in pressure_variables(graph).items()})
    exprs.update({f"signal:{label}": expr for label, expr in (signals or {}).items()})
    for b, end in graph.bonds_of(junction):
        other = graph.elements[b.head.element if end == "tail" else b.tail.element]
        if other.kind in ("C", "I"):
            exprs[f"state:{other.state}"] = other.state
    run_graph, run_experiment = graph, experiment
    if estimate is not None and np.size(estimate) == np.size(experiment.t):
        from .graph_location_graph import corrected
        run_graph, run_experiment, _ = corrected(graph, experiment, junction, estimate)
    values = simulate_expressions(run_graph, run_experiment, exprs, x0=x0)
    if not values:
        return Scales(span=span, dt=dt), {}
    flows = [values[f"f_{b.name}"] for b in bonds]
    efforts = [values[f"e_{b.name}"] for b in bonds]
    if graph.elements[junction].kind == "1":
        flow, effort = flows[0], max(efforts, key=rms)
    else:
        flow, effort = max(flows, key=rms), efforts[0] - np.mean(efforts[0])
    t = np.asarray(experiment.t, dtype=float)
    displacement = np.concatenate([[0.0], np.cumsum(0.5 * (flow[1:] + flow[:-1]) * np.diff(t))])
    displacement = displacement - np.mean(displacement)
    return Scales(flow=_positive(rms(flow)), effort=_positive(max(rms(effort), _measured_effort(graph, junction,
                                                                                             experiment))),
                  displacement=_positive(rms(displacement)), span=span, dt=dt, from_data=True), values


def _measured_effort(graph, junction: str, experiment) -> float:
    """Largest spread of a measured output in the junction's effort unit (a load cell on a rig
    whose nominal model puts no force there: the missing effort is what it measures)."""
    from .catalogue_common import junction_units
    unit = junction_units(graph, junction)[0]
    spreads = [float(np.std(y)) for o, y in experiment.outputs.items()
               if unit and experiment.units.get(o) == unit and np.isfinite(y).all()]
    return max(spreads, default=0.0)


def _positive(value: float) -> float:
    return value if value > 0 and np.isfinite(value) else 1.0


def pressure_variables(graph) -> dict[str, str]:
    """Pressure-like variables of a graph: label -> expression.

    Inputs in Pa, kPa or bar (an imposed chamber pressure), the pressure states
    of pneumatic chambers (``PneumaticC``) and of equation elements in those
    units, and efforts of C elements of the pneumatic and hydraulic domains;
    with two or more, also their mean.
    """
    found = {d.name: d.name for d in graph.inputs() if d.unit in ("Pa", "kPa", "bar")}
    for e in graph.elements.values():
        if e.kind == "PneumaticC":
            found.update({state: state for state in e.states if state != e.gas_state})   # not its temperature
        elif e.kind == "Eq":
            for state in e.states:
                if e.units.get(state, "") in ("Pa", "kPa", "bar"):
                    found[state] = state
        elif e.kind == "C" and getattr(e, "domain", "") in ("pneumatic", "hydraulic"):
            found[f"e_{e.name}"] = f"e_{e.name}"
    if len(found) >= 2:
        found["mean_pressure"] = "(" + " + ".join(found.values()) + f")/{len(found)}"
    return found
