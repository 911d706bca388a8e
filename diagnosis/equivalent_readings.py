"""Scalings no recording of these signals tells apart from an answer: swapped one-parameter readings.

A gain on an input and a storage element's value can be one model.  A force-driven carriage whose
actuator delivers :math:`g F` obeys :math:`m \\dot v = g F - F_f(v)`, which is
:math:`(m/g)\\,\\dot v = F - F_f(v)/g`: on a recording of the force and the motion, a gain error of
the actuator *is* a mass off by :math:`1/g` with every fitted friction level scaled alike.  The
choice names one of the two (whichever its candidates held: a value pair of the mass and a friction,
say), and the answer should say that the other reads the same; before this module it did not
(carriage compound benchmark, seed 4302, cases 008, 016, 022: an input gain answered as the mass's
value, with nothing said).

The test starts local, from structural identifiability by output sensitivities (Brun, Reichert and
Künsch, *Water Resour. Res.* 37, 2001): about the answer's fitted model, the outputs' sensitivities
to its parameters and to its start state span the changes the answer can make.  A *twin* is a
one-parameter reading of the scaling kinds (:data:`TWIN_KINDS`: an input's gain, an output's gain,
an I, C or R element's own value) that the answer does not hold.  It reads as an answered scaling
``E`` (itself one of those kinds) when

1. the twin's sensitivity lies in that span (projection residual at most :data:`TOLERANCE` of its
   own norm): its coefficients :math:`c_j` on the answer's relative sensitivities
   (:math:`\\theta_j\\,\\partial y/\\partial\\theta_j`) say that 1 % of the twin is :math:`c_j` % of
   each value, a direction along which the outputs do not change;
2. that direction moves ``E``'s value (:math:`|c_E| \\ge` :data:`MOVES`): followed as a scaling,
   :math:`T = T_0 e^{\\delta}`, :math:`\\theta_j \\to \\theta_j e^{-c_j\\delta}`, it brings ``E``
   back to where it has no effect (a gain's 1, the element's nominal value) with the twin at a value
   inside its bounds.  A friction's level cannot be swapped so: no finite scaling takes it to
   zero; and
3. that swapped model, simulated (its start state refitted: the symmetry moves a momentum
   :math:`p = m v`), reproduces the answer's outputs within
   :data:`~diagnosis.fit.COLLAPSED` noise standard deviations everywhere on the window.

Step 3 makes the claim global on this recording, not only first order: what is listed is an exact
rescaling of the answer (the carriage's :math:`m/g`), not a near-collinearity, which is the
held-out choice's business.  Rows are the fit window's output samples over each output's noise
standard deviation; derivatives are central differences of relative step :data:`STEP`.
"""
from __future__ import annotations

import numpy as np

from .alternatives import Alternative
from .errors import DiagnosisError
from .place import Place

__all__ = ["TWIN_KINDS", "TOLERANCE", "STEP", "MOVES", "swapped_readings"]

#: kinds whose one parameter scales what the model already has (the twins)
TWIN_KINDS = ("input_gain", "sensor_gain", "nominal_value")
#: most projection residual, relative to the column's own norm, of a reading the answer's span holds
TOLERANCE = 1e-3
#: relative step of the central differences
STEP = 1e-4
#: least share of a twin's change that must fall on an answered scaling for the two to be swapped
MOVES = 1e-2


def swapped_readings(graph, effects, experiment, x0, noise: dict) -> dict[int, list[Alternative]]:
    """The twins (module docstring) each answered effect reads as.

    Parameters
    ----------
    graph : BondGraph
        The answer's model, its fitted values set.
    effects : sequence of Candidate or CandidatePair or CandidateGroup
        The answered effects, one per round (a pair's or a group's members each an effect), as
        proposed on the nominal model (a scaling's guess is where it has no effect: a gain's 1, an
        element's nominal value).
    experiment : Experiment
        The part the sensitivities are taken on (the fits' window).
    x0 : dict or array or None
        Its start state.
    noise : dict str -> float
        Noise standard deviation per measured output (model units): the rows' weights.

    Returns
    -------
    dict int -> list of Alternative
        By index into `effects`: the twins that read as one of its members, each an
        :class:`~diagnosis.alternatives.Alternative` whose ``structural`` says with which values
        (numbers NaN but the largest difference from the answer's outputs: it is not fitted).
        Empty where the answer's run is not finite.
    """
    from .residuals import OutputSimulator

    members = [(i, m) for i, e in enumerate(effects) for m in getattr(e, "members", (e,))]
    outputs = [o for o in experiment.outputs if o in noise and np.isfinite(noise[o]) and noise[o] > 0]
    if not any(m.kind in TWIN_KINDS and m.n_params == 1 for _, m in members) or not outputs:
        return {}
    sim = OutputSimulator(graph, experiment, outputs=outputs)
    known = graph.parameters()
    try:
        base = sim.run(None, x0)
    except DiagnosisError:
        return {}
    weight = np.concatenate([np.full(experiment.t.size, 1.0 / noise[o]) for o in outputs])
    y0 = _stacked(base.outputs, outputs)
    names = list(dict.fromkeys(p.name for _, m in members for p in m.params if p.name in known))
    if not names or not np.all(np.isfinite(y0)):
        return {}
    values = {n: float(known[n].value) for n in names}
    P = np.column_stack([_parameter_column(sim, x0, n, values[n], outputs) for n in names]) * weight[:, None]
    S, _ = _start_columns(sim, x0, base, outputs)
    A = np.column_stack([P, S * weight[:, None]])
    answered = {(m.kind, str(m.place), m.target) for _, m in members}
    found: dict[int, list[Alternative]] = {}
    for twin in _twins(graph, experiment, x0):
        if (twin.kind, str(twin.place), twin.target) in answered or twin.params[0].name in names:
            continue
        col = _twin_column(graph, sim, twin, experiment, x0, outputs, y0)
        if col is None or _residual(A, col * weight) > TOLERANCE:
            continue
        c = np.linalg.lstsq(A, col * weight, rcond=1e-10)[0][:len(names)]
        for i, cand in members:
            if cand.kind not in TWIN_KINDS or cand.n_params != 1 or cand.params[0].name not in values:
                continue
            swap = _swapped(graph, twin, cand, names, values, c, weight, x0, experiment, outputs, y0)
            if swap is not None:
                gap, text = swap
                found.setdefault(i, []).append(Alternative(twin.kind, str(twin.place), {}, float("nan"), gap,
                                                           twin.n_params, structural=text))
    return found


def _swapped(graph, twin, cand, names, values, c, weight, x0, experiment, outputs, y0):
    """``(largest difference in noise standard deviations, the swap in words)`` of the model with
    `cand` back where it has no effect and `twin` moved along the symmetry the coefficients `c`
    describe (:math:`T = T_0 e^{\\delta}`, :math:`\\theta_j \\to \\theta_j e^{-c_j \\delta}`, δ
    chosen to bring `cand`'s value to its guess), its start state refitted; None where the
    symmetry does not move `cand`'s value or the swapped model's outputs differ from the answer's
    by :data:`~diagnosis.fit.COLLAPSED` noise standard deviations or more."""
    from .fit import COLLAPSED
    from .residuals import OutputSimulator
    k = names.index(cand.params[0].name)
    if abs(c[k]) < MOVES or not cand.params[0].guess or values[names[k]] / cand.params[0].guess <= 0:
        return None
    delta = -np.log(cand.params[0].guess / values[names[k]]) / c[k]
    # a relative column's value scales along the symmetry; a value at 0 took an absolute column (_parameter_column)
    moved = {n: values[n] * np.exp(-c[j] * delta) if values[n] else -c[j] * delta for j, n in enumerate(names)}
    moved[names[k]] = float(cand.params[0].guess)
    spec = twin.params[0]
    at = float(spec.guess) * np.exp(delta)
    if not spec.lower <= at <= spec.upper:
        return None
    try:
        swapped = twin.build(graph.with_params(moved), {spec.name: at})
        own = OutputSimulator(swapped, experiment, outputs=outputs)
        x = own.initial_state(x0)
        for _ in range(2):      # the symmetry moves the start state too (a momentum p = m v): refit it
            run = own.run(None, x)
            S, sizes = _start_columns(own, x, run, outputs)
            r = (_stacked(run.outputs, outputs) - y0) * weight
            x = x - np.linalg.lstsq(S * weight[:, None], r, rcond=1e-10)[0] * sizes
        gap = float(np.max(np.abs((_stacked(own.run(None, x).outputs, outputs) - y0) * weight)))
    except DiagnosisError:
        return None
    if not gap < COLLAPSED:
        return None
    changed = [n for n in names if n != names[k] and abs(moved[n] - values[n]) > 1e-3 * abs(values[n])]
    scaled = ", ".join(f"{n} x {moved[n] / values[n]:.3g}" if values[n] else f"{n} = {moved[n]:.3g}" for n in changed)
    return gap, (f"with {cand.params[0].name} back at {cand.params[0].guess:.4g} {cand.params[0].unit}".rstrip()
                 + f", {spec.name} = {at:.3g}" + (f" and {scaled}" if scaled else "")
                 + f" reproduce the answer's outputs to {gap:.2g} noise standard deviations: it is {cand.kind} "
                 f"at {cand.place} rescaled, and the recording cannot tell the two apart")


def _twins(graph, experiment, x0) -> list:
    """The one-parameter readings of :data:`TWIN_KINDS` at every input, output and junction."""
    from .catalogue import candidates
    places = ([Place("input", d.name) for d in graph.inputs() if d.name in experiment.inputs]
              + [Place("output", o) for o in experiment.outputs if o in graph.outputs]
              + [Place("junction", n) for n, e in graph.elements.items() if e.kind in ("0", "1")])
    out, seen = [], set()
    for place in places:
        for cand in candidates(graph, place, experiment=experiment, x0=x0, kinds=TWIN_KINDS):
            key = (cand.kind, tuple(p.name for p in cand.params))
            if cand.n_params == 1 and key not in seen:
                seen.add(key)
                out.append(cand)
    return out


def _stacked(outputs: dict, names) -> np.ndarray:
    return np.concatenate([np.asarray(outputs[o], float) for o in names])


def _parameter_column(sim, x0, name, value, outputs) -> np.ndarray:
    """:math:`\\theta\\,\\partial y/\\partial\\theta` by central differences (absolute step where θ = 0)."""
    h = STEP * abs(value) if value else STEP
    up, down = sim.run_batch([{name: value + h}, {name: value - h}], x0)
    d = (_stacked(up.outputs, outputs) - _stacked(down.outputs, outputs)) / (2 * h)
    return d * (value if value else 1.0)


def _start_columns(sim, x0, base, outputs) -> tuple[np.ndarray, np.ndarray]:
    """``(columns, sizes)``: the outputs' sensitivities to each start state, times the state's
    scale along the run (`sizes`)."""
    x = sim.initial_state(x0)
    out, sizes = [], []
    for i in range(x.size):
        size = max(abs(x[i]), float(np.std(base.states[:, i])), 1e-12)
        h = STEP * size
        up, down = (x.copy(), x.copy())
        up[i] += h
        down[i] -= h
        d = _stacked(sim.run(None, up).outputs, outputs) - _stacked(sim.run(None, down).outputs, outputs)
        out.append(d / (2 * h) * size)
        sizes.append(size)
    n = base.t.size * len(outputs)
    return (np.column_stack(out) if out else np.zeros((n, 0))), np.array(sizes)


def _twin_column(graph, sim, twin, experiment, x0, outputs, y0):
    """The twin's relative sensitivity, or None where it cannot be had (a run that does not stay
    finite; a model whose state vector is not the answer's).  Evaluated on the answer's compiled
    model where the twin's law allows (deriving a pam's equations for each twin cost 0.8 s): an
    output's gain at 1 scales that output (its relative sensitivity is the output itself, as
    ``sensor_gain`` reads it), an input's gain scales the input's departures from where it rests
    (as ``input_gain`` routes it: the recorded input changed instead), and an element's value is a
    parameter of the model; another kind's model is built and compiled."""
    from .graph_location_graph import with_inputs
    from .residuals import OutputSimulator
    spec = twin.params[0]
    known = graph.parameters()
    try:
        if twin.kind == "sensor_gain":
            col = np.concatenate([y0[i * experiment.t.size:(i + 1) * experiment.t.size] if o == twin.place.name
                                  else np.zeros(experiment.t.size) for i, o in enumerate(outputs)])
        elif twin.kind == "input_gain":
            u, rest = twin.place.name, float(twin.constants[0][1])
            recorded = np.asarray(experiment.inputs[u], float)
            runs = [sim.on(with_inputs(experiment, {u: rest + g * (recorded - rest)}, {})).run(None, x0)
                    for g in (1 + STEP, 1 - STEP)]
            col = (_stacked(runs[0].outputs, outputs) - _stacked(runs[1].outputs, outputs)) / (2 * STEP)
        elif spec.name in known:       # a value the model has: the answer's own compiled model
            col = _parameter_column(sim, x0, spec.name, float(known[spec.name].value), outputs)
        else:
            built = twin.build(graph, twin.guesses())
            own = OutputSimulator(built, experiment, outputs=outputs)
            if own.model.state_names != sim.model.state_names:
                return None
            col = _parameter_column(own, x0, spec.name, float(spec.guess), outputs)
    except DiagnosisError:
        return None
    return col if np.all(np.isfinite(col)) and np.any(col) else None


def _residual(A, b) -> float:
    """``|b - P_A b| / |b|`` (P_A the projection on A's column span, columns normalised)."""
    norm = float(np.linalg.norm(b))
    if norm == 0:
        return 0.0
    widths = np.linalg.norm(A, axis=0)
    keep = widths > 0
    if not keep.any():
        return 1.0
    An = A[:, keep] / widths[keep]
    c, *_ = np.linalg.lstsq(An, b, rcond=1e-10)
    return float(np.linalg.norm(b - An @ c) / norm)
