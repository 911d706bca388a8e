"""Where on the graph a mismatch sits: the place whose correction explains the residual.

Method
------
Each candidate :class:`~diagnosis.place.Place` gets a correction with as
much freedom as the physics it stands for, estimated from the recorded
outputs by regularised least squares on the linearised simulation error
(:mod:`diagnosis.graph_location_linear`), then fed back into a full
simulation; the place is scored by the share of the nominal residual it
removes.

* **Junction** (every 0- and 1-junction): the graph gets, for each junction
  at once, an effort source ``Se`` (1-junction) or a flow source ``Sf``
  (0-junction) on a new bond into it, driven by a new input ``d``: an
  unknown extra effort / flow, which is what a missing friction, leak, heat
  flow or stiffness adds there.  A source on a new bond never changes the
  causality of the others, so one augmented graph serves every junction.
  :math:`d(t)` is piecewise linear on K knots (hat functions
  :math:`\\phi_j`), :math:`d = \\sum_j \\theta_j \\phi_j(t)`, found by

  .. math::

      \\min_\\theta \\sum_o w_o \\lVert r_o - S_o \\theta \\rVert^2
      + \\lambda \\lVert \\Delta^2 \\theta \\rVert^2,

  with :math:`r_o` the nominal residual of output o, :math:`S_o` its
  linearised response to each hat function, :math:`w_o = 1/\\sigma_o^2`
  (measurement noise, :func:`diagnosis.residuals.noise_sigma`) and
  :math:`\\lambda` by generalised cross-validation [1]_ (a random-walk prior
  on d, as in an augmented-state smoother, in its least-squares form).
* **Input** (every recorded input): an actuator correction, the input the
  model should have received minus the recorded one,
  :math:`\\delta u = g(u) + c\\,(L u - u)`: :math:`g` piecewise linear in
  :math:`u` (offset, gain and hinges at the 10/30/50/70/90 % quantiles of
  :math:`u`: saturation, dead zone) and :math:`L` a first-order lag or a
  pure delay of 3, 10, 30 or 100 sample intervals (the best of the eight).
  A free :math:`\\delta u(t)` would be the same as an extra effort at the
  source's junction; the structured one says "the actuator is wrong", not
  "something at this junction".
* **Output** (every measured output): a sensor correction
  :math:`\\delta y = a + b\\,\\hat y` (offset, gain) of that output alone, with hinges
  at its range's ends (a clipping sensor) or a first-order lag of it (a sensor's own
  dynamics) where they pay for themselves.  A free correction would explain any residual by
  construction.

Score (``PlaceScore.explained``): with :math:`E_0` the weighted sum of
squared nominal residuals and :math:`E_1` that after the correction (full
simulation), the share removed beyond what fitting noise alone would remove,

.. math::

    \\text{explained} = \\max\\left(0, \\frac{E_0 - E_1 - \\nu}{E_0}\\right),

where :math:`\\nu` is the correction's effective number of parameters (trace
of the hat matrix; 2 for a sensor, the rank of the static terms + 2 for an
actuator): each fitted degree of
freedom removes about :math:`\\sigma^2` of pure noise (an adjusted
:math:`R^2`).  An un-perturbed recording so scores about 0 everywhere.
Places are ranked by the score with a small preference (0.01) for the
simpler place at near ties: output, then input, then junction.

References
----------
.. [1] G. H. Golub, M. Heath, G. Wahba, "Generalized cross-validation as a
   method for choosing a good ridge parameter", Technometrics 21 (1979) 215-223.
"""
from __future__ import annotations

import sys
from dataclasses import dataclass

import numpy as np

from .graph_location_graph import augment, junction_unit, report_bond, with_inputs
from .place import Place
from .errors import DiagnosisError

__all__ = ["PlaceScore", "candidate_places", "locate_on_graph"]

_SIMPLICITY = {"output": 0.0, "input": 0.5, "junction": 1.0, "law": 1.5}   # x 0.01 preference
_TIE_PREFERENCE = 0.01
_RESPONSE_BUDGET = 2e7     # stored response entries (rows x outputs x sequences)
_MAX_ROWS = 10000          # rows kept for the least squares (longer runs are strided)
_MAX_KNOTS = 500
_MIN_KNOTS = 8
_LAGS = (0.5, 3.0, 10.0, 30.0, 100.0)   # actuator lag / delay grid, multiples of the median sample interval
_HINGES = (0.1, 0.3, 0.5, 0.7, 0.9)  # quantiles of the input where its static correction may bend


@dataclass
class PlaceScore:
    """How much of the residual a correction at one place explains.

    Attributes
    ----------
    place : Place
    explained : float
        Share of the nominal residual (noise-weighted sum of squares over the
        measured outputs) removed by the correction, in [0, 1], net of what
        fitting noise would remove (see the module docstring).
    estimate : ndarray, shape (n,)
        The estimated correction at the experiment's times: extra effort
        (1-junction) or flow (0-junction) into the junction, the additive
        correction of the input, or of the output.
    unit : str
        Unit of `estimate`.
    bond : str or None
        For a junction, a bond of it (its storage element's, else a named
        one) to report the location by; None for inputs and outputs.
    dof : float
        Effective number of fitted parameters of the correction.
    window : (float, float) or None
        First and last time of the window the score was computed on, s; None: the whole
        experiment.
    """

    place: Place
    explained: float
    estimate: np.ndarray
    unit: str
    bond: str | None
    dof: float = 0.0
    window: tuple | None = None


def candidate_places(model, *, experiment=None) -> list[Place]:
    """Every junction, every input and every output of a model, and every law place
    (:mod:`diagnosis.law_places`: a constitutive law whose bond ends at no junction).

    Parameters
    ----------
    model : BondGraph or StateEquations
        A StateEquations has no junctions: inputs and outputs only.
    experiment : Experiment, optional
        If given, only the inputs it records (bound) and the outputs it measures.

    Returns
    -------
    list of Place
        Junctions (in the graph's order), then inputs, then outputs, then laws.

    Examples
    --------
    >>> from plants import library
    >>> [str(p) for p in candidate_places(library.build("rlc"))]
    ['junction i_loop', 'input V', 'output v_C', 'output i']
    """
    from bondgraph import BondGraph

    eqs = model.equations() if isinstance(model, BondGraph) else model
    places = []
    if isinstance(model, BondGraph):
        places += [Place("junction", name, report_bond(model, name))
                   for name, e in model.elements.items() if e.kind in ("0", "1")]
    inputs = eqs.input_names if experiment is None else [n for n in eqs.input_names if n in experiment.inputs]
    outputs = tuple(eqs.outputs) if experiment is None else [n for n in eqs.outputs if n in experiment.outputs]
    places += [Place("input", n) for n in inputs]
    places += [Place("output", n) for n in outputs]
    if isinstance(model, BondGraph):
        from .law_places import law_places
        places += law_places(model)
    return places


def locate_on_graph(model, experiment, *, places=None, progress=False, x0=None,
                    _spacing=None) -> list[PlaceScore]:
    """Rank places of a model by the share of the recorded residual a correction there explains.

    Parameters
    ----------
    model : BondGraph or StateEquations
        The nominal model (a StateEquations offers input and output places only).
    experiment : Experiment
        Recorded inputs and measured outputs, model units.
    places : iterable of Place, optional
        Default :func:`candidate_places` of the model for this experiment.
    progress : bool
        Print one line per step to stderr.
    x0 : dict str -> float, optional
        State at the experiment's first sample (default: the model's initial state).

    Returns
    -------
    list of PlaceScore
        Best first (see the module docstring for the method and the score).  When the
        junction knots spread over the whole record could not follow the residual's band
        (:mod:`diagnosis.graph_location_band`), the junctions are scored on one window of the
        record (``PlaceScore.window``; their estimates are NaN outside it), the inputs and
        outputs on the whole record.

    Raises
    ------
    DiagnosisError
        No measured output, or a place that is not a junction / recorded input /
        measured output of the model (the known ones are listed).
    """
    from .residuals import OutputSimulator

    outputs = list(experiment.outputs)
    if not outputs:
        raise DiagnosisError(f"{experiment.source}: no measured output to locate a mismatch with")
    known = candidate_places(model, experiment=experiment)
    by_key = {(k.kind, k.name): k for k in known}
    places = known if places is None else list(places)
    for p in places:
        if (p.kind, p.name) not in by_key:
            raise DiagnosisError(f"place {p} is not a junction, recorded input or measured output of "
                                 f"{getattr(model, 'name', 'the model')!r}; known: "
                                 f"{', '.join(map(str, known))}")
    places = [by_key[(p.kind, p.name)] for p in places]      # junctions with their report bond
    if any(p.kind == "law" for p in places):
        # a law place is a junction put into its bond (diagnosis.law_places): locate on that graph
        from .law_places import split_laws
        split, junction_of = split_laws(model, places)
        law_of = {j: p for p, j in junction_of.items()}
        scores = locate_on_graph(split, experiment, places=[Place("junction", junction_of[p]) if p.kind == "law"
                                                            else p for p in places],
                                 progress=progress, x0=x0, _spacing=_spacing)
        for s in scores:
            if s.place.kind == "junction" and s.place.name in law_of:
                s.place, s.bond = law_of[s.place.name], law_of[s.place.name].bond
        return sorted(scores, key=lambda s: -(s.explained - _TIE_PREFERENCE * _SIMPLICITY[s.place.kind]))
    junctions = [p.name for p in places if p.kind == "junction"]
    say = _Say(progress)
    graph, d_inputs = augment(model, junctions) if junctions else (model, {})
    exp = with_inputs(experiment, {d: np.zeros_like(experiment.t) for d in d_inputs.values()},
                      {d: junction_unit(model, j) for j, d in d_inputs.items()})
    say(f"locate: nominal run of {getattr(model, 'name', 'model')} with {len(junctions)} junction source(s)")
    sim = OutputSimulator(graph, exp, outputs=outputs)
    run = sim.run(None, x0)
    ctx = _Context(sim, run, experiment, outputs, x0)
    window = _fine_window(ctx, len(junctions)) if junctions and _spacing is None else None
    if window is not None:
        a, b, spacing = window
        say(f"locate: junction knots {spacing * 1e3:.3g} ms apart to follow the residual's band: "
            f"window {ctx.t[a]:.4g} .. {ctx.t[b - 1]:.4g} s")
        start = {nm: float(v) for nm, v in zip(run.state_names, run.states[a])}
        windowed = locate_on_graph(model, experiment.window(ctx.t[a], ctx.t[b - 1]),
                                   places=[p for p in places if p.kind == "junction"],
                                   progress=progress, x0=start, _spacing=spacing)
        for score in windowed:
            full = np.full(ctx.t.size, np.nan)
            full[a:b] = score.estimate
            score.estimate, score.window = full, (float(ctx.t[a]), float(ctx.t[b - 1]))
        # inputs and outputs have no knots: they are scored on the whole record, where their
        # corrections act from its start.  On the window they would start from the nominal's
        # state there, which a junction's free effort corrects in its first knots and an input's
        # lag cannot (seed 5858, case 012: a 5 ms valve lag's input explained 15 % of the window,
        # 76 % of the record)
        places, junctions = [p for p in places if p.kind != "junction"], []
    else:
        windowed = []
    channels = [d_inputs[j] for j in junctions] + [p.name for p in places if p.kind == "input"]
    lin = None
    if channels:
        from .graph_location_linear import LinearisedResponse
        say("locate: linearising along the nominal run")
        lin = LinearisedResponse(sim.model, run, sim.model.param_vector(None), channels, outputs)
    # the perturbation sequences of every input and junction place, propagated in one pass
    sequences = {}
    # every junction has the same knots: one basis (n x 500, 0.4 s to build on 91 000 samples)
    hats = _hat_basis(ctx.t, _knots(ctx, len(junctions), _spacing)) if junctions else None
    for i, place in enumerate(places):
        if place.kind == "input":
            sequences[i] = (channels.index(place.name), *_input_sequences(ctx, place))
        elif place.kind == "junction":
            sequences[i] = (channels.index(d_inputs[place.name]), hats, None)
    responses = _responses(lin, ctx.rows, {i: (ch, seq) for i, (ch, seq, _) in sequences.items()})
    scores = []
    for i, place in enumerate(places):
        say(f"locate: {place} ({i + 1}/{len(places)})")
        if place.kind == "output":
            scores.append(_score_output(ctx, place))
        elif place.kind == "input":
            scores.append(_score_input(ctx, place, sequences[i][1], sequences[i][2], responses[i]))
        else:
            scores.append(_score_junction(ctx, place, d_inputs[place.name], sequences[i][1], responses[i], graph))
    return sorted(scores + windowed, key=lambda s: -(s.explained - _TIE_PREFERENCE * _SIMPLICITY[s.place.kind]))


class _Say:
    def __init__(self, enabled):
        self.enabled = enabled

    def __call__(self, text):
        if self.enabled:
            print(text, file=sys.stderr, flush=True)


class _Context:
    """Nominal residuals, weights and the stored rows shared by every place."""

    def __init__(self, sim, run, experiment, outputs, x0=None):
        from .residuals import noise_sigma

        self.sim, self.run, self.t, self.outputs, self.x0 = sim, run, run.t, outputs, x0
        #: the median sample interval, s (the grid of the input and output lags)
        self.dt = float(np.median(np.diff(self.t))) if self.t.size > 1 else 1.0
        self.measured = {o: np.asarray(experiment.outputs[o], dtype=float) for o in outputs}
        self.residual = {o: self.measured[o] - run.outputs[o] for o in outputs}
        self.weight = {}
        for o in outputs:
            y = self.measured[o]
            sigma = max(noise_sigma(y, self.residual[o]), 1e-3 * float(np.std(y)), 1e-12 * max(1.0, float(np.max(np.abs(y)))))
            self.weight[o] = 1.0 / sigma ** 2
        self.e0 = self.energy(run.outputs)
        n = self.t.size
        self.rows = np.arange(0, n, max(1, int(np.ceil(n / _MAX_ROWS))))
        self.r_rows = np.stack([self.residual[o][self.rows] for o in outputs], axis=1)  # (rows, ny)
        self.w = np.array([self.weight[o] for o in outputs])

    def energy(self, simulated) -> float:
        """Noise-weighted sum of squared residuals of `simulated` (dict by output)."""
        return float(sum(self.weight[o] * np.sum((self.measured[o] - simulated[o]) ** 2) for o in self.outputs))

    def share(self, e1: float, dof: float) -> float:
        if not np.isfinite(e1) or self.e0 <= 0:
            return 0.0
        return float(np.clip((self.e0 - e1 - dof) / self.e0, 0.0, 1.0))

    def simulate_with(self, column: str, values) -> dict | None:
        """Outputs with input `column` replaced by `values` (None if the simulation fails)."""
        return self.simulate_each(column, [values])[0]

    def simulate_each(self, column: str, candidates) -> list:
        """:meth:`simulate_with` for each of `candidates`, on as many threads as there are
        cores (:func:`bondgraph.numerics.threads.worker_threads`; the C loop releases the GIL)."""
        from concurrent.futures import ThreadPoolExecutor

        from bondgraph.numerics.threads import worker_threads
        from diagnosis.errors import BondcosimError

        def one(values):
            try:
                return self.sim.with_input(column, values).run(None, self.x0).outputs
            except (BondcosimError, FloatingPointError, np.linalg.LinAlgError):
                return None

        workers = min(len(candidates), worker_threads())
        if workers <= 1:
            return [one(v) for v in candidates]
        with ThreadPoolExecutor(max_workers=workers) as pool:
            return list(pool.map(one, candidates))


#: quantiles of the simulated output at which a sensor's range may begin (hinges of the correction)
_RANGE_QUANTILES = (0.03, 0.1, 0.25, 0.75, 0.9, 0.97)


def _score_output(ctx, place) -> PlaceScore:
    """Sensor correction of one output: ``a + b*y_hat`` plus hinges ``max(y_hat - c, 0)`` /
    ``min(y_hat - c, 0)`` at quantiles of ``y_hat`` (a sensor that clips at the ends of its
    range), or plus ``c (L y_hat - y_hat)`` with ``L`` a first-order lag from the grid
    :data:`_LAGS` (a sensor's own dynamics, one degree of freedom more for the lag chosen),
    exact linear least squares; the hinges or the lag are kept only when they pay for their
    degrees of freedom.  Without the lag a heater block's sensor lag of 25 s left its output
    12 % of the residual, below three places where an actuator lag explained it all."""
    o = place.name
    y_hat = ctx.run.outputs[o]
    linear = np.stack([np.ones_like(y_hat), y_hat - np.mean(y_hat)], axis=1)
    cuts = np.quantile(y_hat, _RANGE_QUANTILES)
    hinges = [np.minimum(y_hat - c, 0.0) if q < 0.5 else np.maximum(y_hat - c, 0.0)
              for q, c in zip(_RANGE_QUANTILES, cuts)]
    t, dt = ctx.t, ctx.dt
    # (basis, degrees of freedom beyond its columns: the lag chosen from the grid)
    bases = [(linear, 0.0), (np.column_stack([linear] + hinges), 0.0)]
    bases += [(np.column_stack([linear, _lagged(y_hat, t, k * dt) - y_hat]), 1.0) for k in _LAGS]
    unit = ctx.sim.equations.units.get(o, "")
    best = None
    for basis, chosen in bases:
        coef, *_ = np.linalg.lstsq(basis, ctx.residual[o], rcond=None)
        estimate = basis @ coef
        corrected = dict(ctx.run.outputs)
        corrected[o] = y_hat + estimate
        dof = float(basis.shape[1]) + chosen
        share = ctx.share(ctx.energy(corrected), dof)
        if best is None or share > best.explained:
            best = PlaceScore(place, share, estimate, str(unit), None, dof)
    return best


def _lagged(u, t, tau):
    """First-order lag of a held input, exact for zero-order hold: y' = (u - y)/tau."""
    decay = np.exp(-np.diff(t) / tau)
    if u.size > 1 and np.allclose(decay, decay[0], rtol=1e-9, atol=0.0):   # uniform sampling: a filter
        from scipy.signal import lfilter
        a = float(decay[0])
        y = np.empty_like(u)
        y[0] = u[0]
        # y[k+1] = a y[k] + (1 - a) u[k], started from y[0] = u[0]
        y[1:], _ = lfilter([1.0 - a], [1.0, -a], u[:-1], zi=[a * u[0]])
        return y
    y = np.empty_like(u)
    y[0] = u[0]
    for k in range(u.size - 1):
        y[k + 1] = u[k] + (y[k] - u[k]) * decay[k]
    return y


def _delayed(u, t, tau):
    """The held input delayed by tau, as a held sequence: over each sample interval the mean of
    u(t - tau) (u held from each sample, its first value before the start).  A delay of whole
    samples shifts the record; a shorter one, or a fraction (a 5 ms valve dead time on a 100 Hz
    record), moves that share of each interval to the previous command."""
    if u.size < 2:
        return u.copy()
    h = np.diff(t)
    area = np.concatenate([[0.0], np.cumsum(u[:-1] * h)])      # integral of the held u from t[0]

    def integral(s):
        return np.where(s < t[0], u[0] * (s - t[0]), np.interp(s, t, area))

    out = np.empty_like(u, dtype=float)
    out[:-1] = (integral(t[1:] - tau) - integral(t[:-1] - tau)) / h
    out[-1] = u[max(int(np.searchsorted(t, t[-1] - tau, side="right")) - 1, 0)]
    return out


def _responses(lin, rows, blocks) -> dict:
    """Linearised responses of several blocks ``key -> (channel, sequences (n, m))`` in one pass
    along the run (the propagation loop over the samples dominates; its cost hardly grows with m):
    ``key -> (rows, ny, m)``.  A sequences array shared by several blocks (the junctions' hat
    basis) is passed once."""
    if not blocks:
        return {}
    keys = list(blocks)
    bases, offset = [], {}
    for k in keys:
        seq = blocks[k][1]
        if id(seq) not in offset:
            offset[id(seq)] = sum(b.shape[1] for b in bases)
            bases.append(seq)
    widths = [blocks[k][1].shape[1] for k in keys]
    channel = np.concatenate([np.full(w, blocks[k][0]) for k, w in zip(keys, widths)])
    columns = np.concatenate([offset[id(blocks[k][1])] + np.arange(w) for k, w in zip(keys, widths)])
    base = bases[0] if len(bases) == 1 else np.concatenate(bases, axis=1)
    resp = lin.response(channel, base, rows, columns)
    edges = np.cumsum([0] + widths)
    return {k: resp[:, :, a:b] for k, a, b in zip(keys, edges[:-1], edges[1:])}


def _input_sequences(ctx, place):
    """The correction terms of an input place as columns: the static ones (offset, gain, hinges
    at quantiles of u) then the dynamic ones (lags, then delays); (sequences (n, m), n_static)."""
    u = ctx.run.inputs[:, ctx.sim.model.input_index[place.name]].copy()
    t, dt = ctx.t, ctx.dt
    static = [np.ones_like(u), u]
    for c in np.unique(np.quantile(u, _HINGES)):
        hinge = np.maximum(u - c, 0.0)
        if np.ptp(hinge) > 1e-9 * max(np.ptp(u), 1e-300):
            static.append(hinge)
    dynamic = ([_lagged(u, t, k * dt) - u for k in _LAGS] + [_delayed(u, t, k * dt) - u for k in _LAGS])
    return np.stack(static + dynamic, axis=1), len(static)


def _score_input(ctx, place, sequences, n_static, resp) -> PlaceScore:
    """Actuator correction g(u) + c (L u - u): g piecewise linear in u (offset, gain, hinges
    at quantiles of u: saturation, dead zone), L a first-order lag or a delay from a grid;
    the best dynamic term by linearised least squares (`resp`: the responses to `sequences`,
    :func:`_input_sequences`), then scored by simulation."""
    u = ctx.run.inputs[:, ctx.sim.model.input_index[place.name]].copy()
    best = None
    for j in range(sequences.shape[1] - n_static):
        cols = list(range(n_static)) + [n_static + j]
        coef, sse, rank = _weighted_lstsq(resp[:, :, cols], ctx.r_rows, ctx.w)
        if best is None or sse < best[0]:
            best = (sse, cols, coef, rank)
    _, cols, coef, rank = best
    estimate = sequences[:, cols] @ coef
    simulated = ctx.simulate_with(place.name, u + estimate)
    e1 = ctx.energy(simulated) if simulated is not None else np.inf
    dof = rank + 1.0                       # + the chosen lag / delay
    unit = ctx.sim.equations.units.get(place.name, "")
    return PlaceScore(place, ctx.share(e1, dof), estimate, str(unit), None, dof)


def _weighted_lstsq(S, r, w):
    """Least squares of r (rows, ny) on S (rows, ny, m) with output weights w; (coef, sse, rank)."""
    sw = np.sqrt(w)[None, :, None]
    A = (S * sw).reshape(-1, S.shape[2])
    b = (r * np.sqrt(w)[None, :]).reshape(-1)
    if not (np.isfinite(A).all() and np.isfinite(b).all()):
        return np.zeros(S.shape[2]), np.inf, 0
    coef, _, rank, _ = np.linalg.lstsq(A, b, rcond=None)
    return coef, float(np.sum((A @ coef - b) ** 2)), int(rank)


def _knots(ctx, n_junctions, spacing=None) -> int:
    """Hat functions per junction: a quarter of the rows kept, within the response budget; with a
    knot `spacing` (s, a window of the record), as many as it takes, up to half the rows."""
    n_rows, ny = ctx.r_rows.shape
    budget = _RESPONSE_BUDGET / (n_rows * ny * max(1, n_junctions))
    if spacing is not None:
        wanted = np.ceil((ctx.t[-1] - ctx.t[0]) / spacing) + 1
        return int(np.clip(min(wanted, n_rows // 2, budget), _MIN_KNOTS, _MAX_KNOTS))
    return int(np.clip(min(n_rows // 4, budget), _MIN_KNOTS, _MAX_KNOTS))


def _fine_window(ctx, n_junctions):
    """``(first, stop, spacing)`` of the window the junction knots must be confined to so that
    they follow the residual's band, or None when knots over the whole record do (see
    :mod:`diagnosis.graph_location_band`; the knots are at least two samples apart)."""
    from .graph_location_band import busiest_window, knot_spacing

    t = ctx.t
    if t.size < 4 * _MIN_KNOTS:
        return None
    dt = float(np.median(np.diff(t)))
    sigma = {o: 1.0 / np.sqrt(w) for o, w in ctx.weight.items()}
    spacing = max(knot_spacing(ctx.residual, sigma, dt), 2.0 * dt)
    whole = (t[-1] - t[0]) / (_knots(ctx, n_junctions) - 1)
    if whole <= 2.0 * spacing:
        return None
    length = int((_MAX_KNOTS - 1) * spacing / dt) + 1
    if length >= t.size:
        return None
    a = busiest_window(ctx.residual, ctx.weight, length)
    return a, a + length, spacing


def _score_junction(ctx, place, d_input, hats, resp, graph) -> PlaceScore:
    """Free piecewise-linear extra effort/flow, GCV-regularised, scored by simulation.

    The linearised fit can overrate a wiggly estimate (stick-slip, saturating
    laws the linearisation does not see), so the GCV choice and three smoother
    ones (lambda x 10, 100, 1000) are all simulated and the best score kept.
    """
    unit = junction_unit(graph, place.name)
    best = PlaceScore(place, 0.0, np.zeros_like(ctx.t), unit, place.bond, 0.0)
    if not np.isfinite(resp).all():        # a linearisation that diverged: no estimate here
        return best
    fits = _smooth_fits(resp, ctx.r_rows, ctx.w)
    estimates = [hats @ theta for theta, _ in fits]
    for (theta, dof), estimate, simulated in zip(fits, estimates, ctx.simulate_each(d_input, estimates)):
        e1 = ctx.energy(simulated) if simulated is not None else np.inf
        score = ctx.share(e1, dof)
        if score > best.explained or best.dof == 0.0:
            best = PlaceScore(place, score, estimate, unit, place.bond, float(dof))
    return best


def _hat_basis(t, knots):
    """Hat functions on `knots` equally spaced knots over t: shape (n, knots), rows sum to 1."""
    grid = np.linspace(t[0], t[-1], knots)
    j = np.clip(np.searchsorted(grid, t, side="right") - 1, 0, knots - 2)   # interval of each t
    w = np.clip((t - grid[j]) / (grid[j + 1] - grid[j]), 0.0, 1.0)
    rows = np.arange(t.size)
    out = np.zeros((t.size, knots))
    out[rows, j], out[rows, j + 1] = 1.0 - w, w
    return out


def _smooth_fits(S, r, w, smoother=(1.0, 10.0, 100.0, 1000.0)):
    """Tikhonov fits with a second-difference penalty: lambda by GCV, then `smoother` x it.

    One generalised eigendecomposition :math:`G v = \\mu B v` (:math:`G = S^T W S`,
    :math:`B = \\Delta^{2T}\\Delta^2 + \\epsilon I`, :math:`V^T B V = I`) serves every
    :math:`\\lambda`: :math:`\\theta = V (\\mu + \\lambda)^{-1} V^T S^T W r` and the
    effective number of parameters is :math:`\\nu = \\sum \\mu / (\\mu + \\lambda)`.

    Returns
    -------
    list of (ndarray, shape (K,), float)
        ``(theta, nu)`` per lambda; empty when the place reaches no output.
    """
    from scipy.linalg import eigh

    sw = np.sqrt(w)[None, :, None]
    A = (S * sw).reshape(-1, S.shape[2])
    b = (r * np.sqrt(w)[None, :]).reshape(-1)
    G, g, bb = A.T @ A, A.T @ b, float(b @ b)
    K, M = G.shape[0], A.shape[0]
    D2 = np.diff(np.eye(K), 2, axis=0)
    B = D2.T @ D2 + 1e-8 * np.eye(K)       # the small ridge pins the penalty's null space (a, b t)
    scale = np.trace(G) / np.trace(B)
    if not np.isfinite(scale) or scale <= 0:      # the place does not reach any output
        return []
    mu, V = eigh(G, B)
    mu = np.clip(mu, 0.0, None)
    c = V.T @ g

    def fit(lam):
        theta = V @ (c / (mu + lam))
        return theta, float(np.sum(mu / (mu + lam)))

    def gcv(lam):
        theta, dof = fit(lam)
        sse = max(bb - 2 * theta @ g + theta @ (G @ theta), 0.0)
        return sse * M / max(M - dof, 1.0) ** 2

    lam_gcv = min(scale * np.logspace(-8, 3, 45), key=gcv)
    return [fit(lam_gcv * k) for k in smoother]
