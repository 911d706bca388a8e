"""The diagnosis pipeline: recording + model -> located, named, modelled missing physics.

:func:`diagnose` runs the steps of the package docstring in order:

1. bind the recording to the model (:func:`diagnosis.recording.bind`) and
   split off the held-out tail;
2. simulate the nominal model on the whole recording (the held-out part
   continues from where the training part leaves the states), residuals,
   noise level per output; as many RK4 sub-steps per sample as keep the integration error
   under a tenth of the noise (:func:`diagnosis.residuals.settle_substeps`); the held-out judge (:func:`diagnosis.segments.choose_judge`:
   open-loop, or the segment simulation error where the nominal diverges or drifts),
   by which the nominal and every later model get their held-out NRMSE;
3. significant time windows (:func:`diagnosis.locate.significant_windows`),
   regime variables, graph location on the training part
   (:func:`diagnosis.graph_location.locate_on_graph`; for a diverging nominal on restarted
   windows, :func:`diagnosis.graph_location_segments.locate_on_segments`, and for an unstable one
   on windows as long as the judge's segments too);
4. candidates of the catalogue at the ``top`` places
   (:func:`diagnosis.catalogue.candidates`), each fitted on the training part
   (its first :data:`MAX_FIT_SAMPLES` samples for long recordings, started from
   the same initial state as every whole-recording simulation, never from a
   nominal state that may have drifted; an unstable nominal's on restarted segments,
   :mod:`diagnosis.shooting`) (:func:`diagnosis.fit.fit_candidate`), and a refit of the ``uncertain``
   nominal parameters alone when any are given; the choice by held-out error
   and parsimony (:func:`diagnosis.fit.choose`), ``none`` when nothing
   explains a significant share; the fits of other kinds the held-out part cannot tell apart from
   the answer (:func:`diagnosis.alternatives.indistinguishable`); where that is ``none`` on a
   residual clearly beyond the noise, the best single fits again in pairs
   (:mod:`diagnosis.pairs`) and the choice once more;
5. the improved graph, its held-out NRMSE (same simulation as the nominal
   one), the regime of the chosen place's correction, the explanation;
6. up to ``max_effects - 1`` further rounds: steps 3-5 again on the improved
   graph against its own residual (its held-out NRMSE is the new reference of
   :func:`~diagnosis.fit.choose`, with the same noise floor and parsimony price);
   a further effect is kept only if ``choose`` accepts it, so a recording with
   one effect answers "nothing more" in round 2.  The effects are reported in
   the order they were found (each round explains most of what is left);
7. with two or more effects, a joint refit of all their parameters (and the
   ``uncertain`` ones) on the training part, started from the round-by-round
   values and kept when the held-out excess error does not grow;
8. for an answer that holds a scaling (an element's value, an input's or a sensor's gain), the
   one-parameter scalings that are the same model rescaled on the fits' window, each listed beside
   the effect it reads as (:func:`diagnosis.equivalent_readings.swapped_readings`: a force-driven
   mass's value is its actuator's gain).
"""
from __future__ import annotations

import sys
import time as _time

import numpy as np
from plants import load as load_model

from . import pairs
from .alternatives import unexcited
from .errors import DiagnosisError
from .initial_state import start_inconsistent
from .place_choice import (MIN_PLACE_SHARE, actuator_places, companions, further_places, located_places, on_storage,
                           sensor_places, spring_places, without_companions)
from .rounds import JointRefit, Round
from .shooting import fitted_from

__all__ = ["diagnose", "MIN_PLACE_SHARE", "MAX_FIT_SAMPLES"]

#: candidates are fitted on at most this many training samples (the start of the training
#: part, from the recording's initial state): a fit runs ~100 simulations
MAX_FIT_SAMPLES = 15000


class _Progress:
    """``diagnose: [  12.3 s] step`` lines on stderr."""

    def __init__(self, enabled: bool):
        self.enabled, self.start, self.timings, self._last = enabled, _time.perf_counter(), {}, None

    def __call__(self, step: str, detail: str = ""):
        now = _time.perf_counter()
        if self._last is not None:
            name, since = self._last
            self.timings[name] = self.timings.get(name, 0.0) + now - since
        self._last = (step, now)
        if self.enabled:
            print(f"diagnose: [{now - self.start:7.1f} s] {step}{': ' + detail if detail else ''}",
                  file=sys.stderr, flush=True)

    def done(self):
        self("done")
        self.timings.pop("done", None)
        self.timings["total"] = _time.perf_counter() - self.start
        return self.timings


def _as_recording(recording, time):
    from .recording import Recording
    if isinstance(recording, Recording):
        return recording
    return Recording.from_csv(recording, time=time)


def _merge(windows):
    out = []
    for a, b in sorted(windows):
        if out and a <= out[-1][1]:
            out[-1][1] = max(out[-1][1], b)
        else:
            out.append([a, b])
    return [(a, b) for a, b in out]


def _with_values(graph, values: dict):
    """A copy of `graph` whose parameters named in `values` take those values (SI)."""
    from .errors import UnknownNameError
    if not values:
        return graph
    try:
        return graph.with_params({name: float(value) for name, value in values.items()})
    except UnknownNameError:
        wrong = sorted(set(values) - set(graph.parameters()))
        raise DiagnosisError(f"cannot set fitted parameter(s) {', '.join(wrong)} in graph {graph.name!r}") from None


def _start_estimator(train, noise, scales, states):
    """``start(simulator, params)``: the initial state of `states` (the nominal model's) estimated in
    a candidate's compiled model at `params` on the first samples of `train`, as the nominal's was
    (:func:`diagnosis.initial_state.estimate_initial_state`; its added states stay at theirs)."""
    from .initial_state import estimate_initial_state

    def start(simulator, params):
        est = estimate_initial_state(simulator, train, noise, scales=scales, params=params, states=states)
        return {name: est.values[name] for name in states}
    return start


def _chosen_start(chosen, x0, start):
    """``(x0, description)``: the chosen fit's own start state (``extra["x0"]``, estimated in its
    model) where it has one, else `x0` and `start` as they were."""
    own = chosen.extra.get("x0")
    if not own:
        return x0, start
    return own, f"{start}, re-estimated with {chosen.candidate} (it acts on those samples)"


def _fit_window(train, run, x0):
    """The training samples the fits use: all, or the first :data:`MAX_FIT_SAMPLES`.

    Both start from `x0` (the recording's initial state, as every whole-recording
    simulation does).  A window later in the record would have to start from the
    nominal simulation's state there, which has drifted away from the plant's
    wherever the nominal model integrates what it leaves out (a force-driven
    mass without its friction): the candidate would be fitted from a wrong state.
    `run` (the nominal run) is not used; it is kept for the callers' symmetry.
    """
    n = train.t.size
    if n <= MAX_FIT_SAMPLES:
        return train, x0
    part = train.window(float(train.t[0]), float(train.t[MAX_FIT_SAMPLES - 1]))
    return part, x0


class _Diverged(str):
    """The message of a nominal simulation's divergence (``""``: it did not diverge), with the
    time it left the finite numbers (``at``, s; None when unknown)."""
    at = None


def _nominal_residuals(sim, graph, exp, x0):
    """The nominal residuals from `x0`, and ``""`` or the message of its divergence
    (a :class:`_Diverged`)."""
    from .errors import SimulationError
    from .residuals import residuals
    try:
        return residuals(graph, exp, simulator=sim, x0=x0), _Diverged("")
    except SimulationError as exc:        # evidence of missing physics, not an error
        message = _Diverged(str(exc))
        message.at = exc.time
        return _diverged_residuals(sim, exp), message


def _before_divergence(part, diverged):
    """The fit window of a diverging nominal: the samples of `part` before 90 % of the time it
    ran finite (every candidate starts from the nominal's values, which would diverge later);
    `part` itself when the time is unknown or too few samples are left."""
    if not diverged or diverged.at is None:
        return part
    t0 = float(part.t[0])
    stop = t0 + 0.9 * (float(diverged.at) - t0)
    if np.count_nonzero(part.t <= stop) < 20 or stop >= part.t[-1]:
        return part
    return part.window(t0, stop)


def _diverged_residuals(sim, experiment):
    """Residuals of a nominal model whose simulation left the finite numbers: NaN simulated
    outputs and states (nothing of the run is used), noise from the measurements alone."""
    from .residuals import Residuals, SimRun, noise_sigma
    n = experiment.t.size
    m = sim.model
    nan = {o: np.full(n, np.nan) for o in sim.output_names}
    measured = {o: np.asarray(experiment.outputs[o], dtype=float) for o in sim.output_names}
    run = SimRun(experiment.t, np.full((n, len(m.state_names)), np.nan), sim.U, nan, m.state_names,
                 m.input_names, 1)
    return Residuals(experiment.t, measured, nan, dict(nan), {o: noise_sigma(y) for o, y in measured.items()},
                     {o: float("inf") for o in measured}, run)


def _restarted_places(graph, train, noise, judge, found, top, say, progress) -> tuple[list, list]:
    """Where the segment judge took an unstable nominal, ``(places, scores)``: the places graph
    location finds on windows of the training part as long as the judge's segments, each
    restarted from a state fitted to the data
    (:func:`diagnosis.graph_location_segments.locate_on_segments`), that are not in `found`, and
    all its scores.

    Along the one nominal run, an unstable nominal's linearisation means little once the run has
    left the data: a pendulum driven over the top by a torque, its pivot friction missing, turns
    a revolution behind within seconds, and a sensor gain explained 98 % of that drift while the
    pivot's 1-junction explained none."""
    from .graph_location_segments import locate_on_segments
    say("graph location", f"restarted windows of {judge.plan.seconds:.3g} s (the segment judge's)")
    try:
        scores = locate_on_segments(graph, train, noise, length=judge.plan.length, progress=progress)
    except (np.linalg.LinAlgError, FloatingPointError):
        return [], []
    known = {(p.kind, p.name) for p in found}
    return [s.place for s in located_places(without_companions(graph, scores), top)
            if (s.place.kind, s.place.name) not in known], scores


def _every_place(graph, experiment):
    """Every junction, recorded input, measured output and law place of `graph`: the places tried when no
    graph location is possible (a diverging nominal has no run to linearise along)."""
    from .place import Place
    from .law_places import acts_on, law_places
    junctions = [Place("junction", n) for n, e in graph.elements.items() if e.kind in ("0", "1")]
    # a law acting on a junction is fitted as its companion (diagnosis.place_choice), not as a place
    laws = [p for p in law_places(graph) if acts_on(graph, p) is None]
    return (junctions + [Place("input", n) for n in experiment.inputs]
            + [Place("output", n) for n in experiment.outputs] + laws)


def _holdout_nrmse(sim, params, x0, judge):
    """The held-out NRMSE of `sim`'s model by `judge` (:mod:`diagnosis.segments`), its open-loop
    outputs and the whole :class:`~diagnosis.segments.Judged`."""
    judged = judge.evaluate(sim, params, x0)
    return judged.nrmse, judged.y, judged


def _noise_overrides(noise, exp) -> dict:
    """`noise` (dict output -> sigma, or ``"NAME=SIGMA[:UNIT]"`` strings) in the outputs' model units."""
    from .units import convert
    if not noise:
        return {}
    items = noise.items() if isinstance(noise, dict) else (
        (text.split("=", 1) if isinstance(text, str) and "=" in text else (text, None)) for text in noise)
    out = {}
    for name, value in items:
        if name not in exp.outputs:
            raise DiagnosisError(f"noise: {name!r} is not a measured output; measured: {', '.join(exp.outputs)}")
        unit = exp.units.get(name, "")
        if isinstance(value, str) and ":" in value:
            value, unit_given = value.split(":", 1)
            try:
                value = float(convert(float(value), unit_given.strip(), unit))
            except ValueError as exc:
                raise DiagnosisError(f"noise of {name}: {exc}") from exc
        try:
            sigma = float(value)
        except (TypeError, ValueError):
            raise DiagnosisError(f"noise of {name}: {value!r} is not a number (NAME=SIGMA[:UNIT])") from None
        if not np.isfinite(sigma) or sigma <= 0:
            raise DiagnosisError(f"noise of {name}: the standard deviation must be positive and finite; "
                                 f"found {sigma!r}")
        out[name] = sigma
    return out


def diagnose(graph, recording, *, inputs, outputs, time=None, holdout: float = 0.3, uncertain=(),
             top: int = 3, progress: bool = False, x0=None, max_effects: int = 2, noise=None,
             spikes: str = "repair"):
    """Locate, name and model what a model leaves out of a recording.

    Parameters
    ----------
    graph : BondGraph or str
        The nominal model, or a built-in model name / ``.json`` or ``.py`` model file
        (:func:`plants.load`).
    recording : Recording or str or path-like
        The recording, or a CSV file (:meth:`Recording.from_csv`).
    inputs, outputs : iterable of str or Binding, or dict str -> str
        ``"NAME=COLUMN[:UNIT]"`` bindings of model inputs (recorded, zero-order
        held) and measured model outputs.
    time : str, optional
        Time column of a CSV, optionally ``"COLUMN:UNIT"``.
    holdout : float
        Fraction of the time span, at the end, held out of location and fitting.
    uncertain : iterable of str
        Nominal parameters fitted alongside each candidate (within a factor 3).
    top : int
        Number of best-ranked graph places whose candidates are fitted.
    progress : bool
        Progress lines (step, elapsed time) on stderr.
    x0 : dict str -> float, optional
        Initial state of the nominal model at the first sample (default: its own).
    max_effects : int
        Most missing effects reported: after the first, each further round looks for
        one more on the improved graph, kept only if it improves the held-out error
        beyond the noise floor and the parsimony price (1: the single-effect answer).
    noise : dict str -> float or iterable of str, optional
        Known measurement-noise standard deviations of some outputs, in the output's
        model unit (or ``"NAME=SIGMA[:UNIT]"``); the others are estimated from the
        recording and the nominal residual (:func:`diagnosis.residuals.noise_sigma`).
    spikes : {"repair", "keep"}
        ``"repair"``: single samples of an output that a sensor glitch put there (many noise
        standard deviations off their neighbours, where the model, the inputs and the other
        outputs are not) are replaced by the mean of their neighbours before anything else,
        and the report names them (:mod:`diagnosis.outliers`); ``"keep"``: used as recorded.

    Returns
    -------
    DiagnosisReport

    Raises
    ------
    RecordingError, UnitError, UnknownNameError
        Bad recording or bindings (named).
    DiagnosisError
        Bad arguments.
    """
    from .catalogue import candidates
    from .fit import fit_candidate, noise_floor
    from .fit_in_turn import fit_in_turn, member_refits
    from .graph_location import locate_on_graph
    from .initial_state import estimate_initial_state
    from .locate import locate_regime, regime_variables, significant_windows
    from .outliers import isolated_spikes, spike_notes, without_spikes
    from .recording import bind
    from .residuals import OutputSimulator, residuals, settle_substeps
    from .segments import choose_judge

    if spikes not in ("repair", "keep"):
        raise DiagnosisError(f"spikes must be 'repair' or 'keep'; found {spikes!r}")
    if int(top) < 1:
        raise DiagnosisError(f"top must be a positive number of places; found {top!r}")
    if isinstance(max_effects, bool) or not isinstance(max_effects, (int, np.integer)) or max_effects < 1:
        raise DiagnosisError(f"max_effects must be a positive whole number of effects; found {max_effects!r}")
    say = _Progress(progress)
    say("reading and binding the recording")
    graph = load_model(graph)
    rec = _as_recording(recording, time)
    exp = bind(rec, graph, inputs, outputs)
    train, held = exp.split(holdout)

    say("nominal simulation", f"{exp.t.size} samples, {exp.span[1] - exp.span[0]:.4g} s")
    sim = OutputSimulator(graph, exp)
    res, diverged = _nominal_residuals(sim, graph, exp, x0)
    res.noise.update(_noise_overrides(noise, exp))
    glitches = isolated_spikes(exp, res.run.outputs, res.noise, res.run.states) if spikes == "repair" else {}
    if glitches:
        say("isolated spikes", "; ".join(f"{o}: {len(i)} sample(s) replaced" for o, i in glitches.items()))
        exp = without_spikes(exp, glitches)
        train, held = exp.split(holdout)
        sim = sim.on(exp)
        # the inputs are the same: the nominal's run (or its divergence) stands, the residuals are new
        res = _diverged_residuals(sim, exp) if diverged else residuals(graph, exp, simulator=sim, run=res.run)
        res.noise.update(_noise_overrides(noise, exp))
    n_train = train.t.size
    start = "the given initial state" if x0 is not None else "the model's initial state"
    estimated = None                 # (the states' scales,) where the start was estimated
    if x0 is None and start_inconsistent(res, diverged, n_train):
        say("initial state", "fitted to the first samples")
        scales = ({nm: float(np.std(res.run.states[:, i])) for i, nm in enumerate(res.run.state_names)}
                  if not diverged else None)
        est = estimate_initial_state(sim, train, res.noise, scales=scales)
        start = est.description
        if est.samples:
            x0 = est.values
            estimated = (scales,)
            res, diverged = _nominal_residuals(sim, graph, exp, x0)
            res.noise.update(_noise_overrides(noise, exp))
    # a diverging nominal has no run to refine (settle_substeps would find it diverge again)
    exp, rule = (exp, exp.substeps) if diverged else settle_substeps(sim, x0, res.noise, run=res.run)
    if exp.substeps > rule:
        say("integration", f"{exp.substeps} RK4 sub-steps per sample, not {rule}: halving the step moved the "
                           "nominal's outputs by more than a tenth of their noise")
        train, held = exp.split(holdout)
        sim = sim.on(exp)
        res, diverged = _nominal_residuals(sim, graph, exp, x0)
        res.noise.update(_noise_overrides(noise, exp))
    floor = noise_floor(held, res.noise)
    measurement_floor = dict(floor)
    # a candidate's model re-estimates the start where the nominal's was estimated
    own_start = _start_estimator(train, res.noise, estimated[0], list(x0)) if estimated else None
    say("held-out judge")
    judge, nominal_judged = choose_judge(sim, exp, held, res, diverged, floor, x0)
    nominal = dict(nominal_judged.nrmse)
    if judge.floor:                  # the segment error's own floor: noise plus the restarts' noise
        floor = dict(judge.floor)
    if judge.kind == "segments":
        say("held-out judge", f"segment simulation error: {judge.reason}")
    restarted_scores = []             # graph location on restarted windows (_restarted_places)
    if diverged:
        from .graph_location_segments import locate_on_segments
        say("nominal diverges", diverged)
        windows, rv, flagged = [], {}, []
        say("graph location", "restarted windows of the training part")
        scores = locate_on_segments(graph, train, res.noise, progress=progress)
        place_list = ([s.place for s in without_companions(graph, scores)[:int(top)]
                       if s.explained >= MIN_PLACE_SHARE] or _every_place(graph, exp))
    else:
        windows = _merge([w for o in exp.outputs
                          for w in significant_windows(exp.t, res.residual[o], res.noise[o])])
        # the outputs whose training residual exceeds the noise somewhere: where round 1 finds none,
        # their sensors are fitted too (below)
        flagged = [o for o in exp.outputs
                   if significant_windows(exp.t[:n_train], res.residual[o][:n_train], res.noise[o])]
        say("regime variables")
        rv_full = regime_variables(graph, exp, res.run)
        rv = {k: (v[:n_train], d) for k, (v, d) in rv_full.items()}
        say("graph location", "training part")
        try:
            scores = locate_on_graph(graph, train, progress=progress, x0=x0)
        except (np.linalg.LinAlgError, FloatingPointError) as exc:   # numerics, not the user's input
            raise DiagnosisError(f"graph location of {graph.name!r} failed on {rec.source}: "
                                 f"{type(exc).__name__}: {exc}") from exc
        place_list = [s.place for s in located_places(without_companions(graph, scores), int(top))]
        if judge.unstable:                # a nominal whose error grows exponentially: also restarted windows
            restarted, restarted_scores = _restarted_places(graph, train, res.noise, judge, place_list, int(top),
                                                            say, progress)
            place_list += restarted
        place_list += actuator_places(graph, place_list, train)

    # a diverging nominal's candidates take their scales from where it still runs
    cand_part = _before_divergence(train, diverged)
    springs = spring_places(graph, place_list)      # the storage kinds only (place_choice.spring_places)
    # a nominal whose open-loop run is mostly drift: the kinds read their junction's values along
    # the run the located correction keeps on the recording (catalogue_scales.junction_scales)
    along = {s.place: s.estimate for s in scores} if judge.kind == "segments" and not diverged else {}
    cands = [c for p in place_list + springs
             for c in candidates(graph, p, regime_variables=rv, experiment=cand_part, x0=x0, estimate=along.get(p))
             if p not in springs or on_storage(graph, c)]
    place_list += springs
    # the feature regression runs along the nominal run: none where it diverges, nor where its mode is
    # unstable (the run has left the plant's motion within seconds): every candidate is fitted
    evidence, cands, pruned = _features(graph, [] if diverged or judge.unstable else scores, place_list, train, x0,
                                        rv, cands, say, "feature regression", restart=_restart(judge))
    fit_part, fit_x0 = _fit_window(train, res.run, x0)
    fit_part = _before_divergence(fit_part, diverged)

    def fit_one(cand, abandon_above):
        # every fit starts at the recording's first sample, where an added actuator still rested
        return fit_candidate(graph, cand, fit_part, held, uncertain=uncertain, x0=fit_x0, through=train,
                             mid_run=False, abandon_above=abandon_above, judge=judge, start=own_start)

    round_part, round_x0, start_x0 = fit_part, fit_x0, x0     # the backfit's, on the nominal model
    fits, best = fit_in_turn(cands, fit_one, say, "fitting")
    fits += _companion_fits(graph, fits, place_list, cand_part, rv, fit_one, say, "fitting", best, x0)
    fits += _twin_fits(graph, fits, cand_part, rv, fit_one, say, "fitting", best, x0, len(place_list))
    if int(max_effects) >= 2:      # an effect beside a storage value a few per cent off (pairs.value_pairs)
        valued = fit_in_turn(pairs.value_pairs(fits, evidence=_lookup(evidence)), fit_one, say, "fitting", best=best,
                             suffix=", with values")[0]
        fits = member_refits(fits + pairs.finishing(valued, floor), fit_one, say, "fitting", "nominal_value")
    if uncertain:
        say("fitting", f"nominal parameters {', '.join(uncertain)} alone")
        fits.append(fit_candidate(graph, None, fit_part, held, uncertain=uncertain, x0=fit_x0,
                                  through=train, judge=judge))

    def choose_round_one():
        say("choosing")
        segments = judge.kind == "segments"
        return _choose(nominal, fits, floor, evidence, res, exp, train, held, diverged or judge.kind != "open-loop",
                       sim, open_loop=(nominal_judged.open_loop, measurement_floor) if segments else None,
                       held_nominal=(nominal_judged.segments if segments and not diverged and not judge.unstable
                                     and _finite_over(res.simulated, n_train) else None), unstable=judge.unstable)

    chosen, alternatives = choose_round_one()

    def sensor_candidates(outputs, located=()):
        """The sensor candidates at `outputs` not among the places `located`, on the nominal model."""
        return [c for p in sensor_places(located, train) if p.name in outputs
                for c in candidates(graph, p, regime_variables=rv, experiment=cand_part, x0=start_x0)
                if c.definition.unranked_sensor]

    sensor_cands = sensor_candidates(flagged, place_list) if chosen is None else []
    if sensor_cands:
        # a sensor's error (a range clipping a few brief excursions) shows on its own output only,
        # and the location may score it far below the junctions behind that output, which explain
        # the same samples through fast dynamics: further rounds fit the sensors wherever something
        # was located (place_choice.further_places); round 1 does where it found nothing else
        sensor_fits, _ = fit_in_turn(sensor_cands, fit_one, say, "fitting sensors", best=best)
        if sensor_fits:
            fits += sensor_fits
            chosen, alternatives = choose_round_one()
    fitted_pairs = False

    def with_pairs(singles=True):
        nonlocal fitted_pairs
        fitted_pairs = True
        # the kinds the features select together first (pairs.selected_pairs), then the best singles'
        selected = pairs.selected_pairs(fits, evidence.values(), looked_ahead=False)
        more = pairs.pair_candidates(fits, besides=selected) if singles else []
        pair_fits, _ = fit_in_turn(selected + more, fit_one, say, "fitting pairs", best=best)
        fits.extend(pair_fits)
        return choose_round_one() if pair_fits else None

    if chosen is None and int(max_effects) >= 2 and pairs.wanted(nominal, floor):
        chosen, alternatives = with_pairs() or (chosen, alternatives)

    x0_nominal, start_nominal = x0, start

    def improved_model(chosen):
        """``(graph, held-out NRMSE, outputs, judged, x0, start)`` of the nominal model with `chosen`."""
        if chosen is None:
            return graph, dict(nominal), res.run.outputs, nominal_judged, x0_nominal, start_nominal
        cand_names = {p.name for p in chosen.candidate.params} if chosen.candidate else set()
        base = (chosen.candidate.build(graph, {k: v for k, v in chosen.values.items() if k in cand_names})
                if chosen.candidate is not None else graph)
        built = _with_values(base, {k: v for k, v in chosen.values.items() if k not in cand_names})
        x_start, described = _chosen_start(chosen, x0_nominal, start_nominal)
        return (built, *_holdout_nrmse(OutputSimulator(built, exp), None, x_start, judge), x_start, described)

    def round_one(chosen, alternatives):
        alternatives = alternatives + unexcited(graph, chosen, cand_part, start_x0)
        return Round(chosen, fits, dict(nominal), dict(improved), seconds=_time.perf_counter() - say.start,
                     diverged=diverged, window=[float(fit_part.t[0]), float(fit_part.t[-1])], floor=floor,
                     start=fitted_from(judge, fit_part, start), restarted=restarted_scores,
                     features=list(evidence.values()), pruned=pruned, indistinguishable=alternatives)

    say("improved model")
    improved_graph, improved, y_imp, improved_judged, x0, start = improved_model(chosen)
    rounds = [round_one(chosen, alternatives)]

    if chosen is not None and chosen.candidate is not None:
        while sum(pairs.effect_count(r.chosen.candidate) for r in rounds if r.chosen is not None) < int(max_effects):
            start = _time.perf_counter()
            found = _further_round(improved_graph, exp, train, held, judge, x0, improved, floor,
                                   rounds, top=int(top), say=say, label=f"round {len(rounds) + 1}", start=own_start)
            found.seconds = _time.perf_counter() - start
            rounds.append(found)
            if found.chosen is None:
                break
            x0 = found.chosen.extra.get("x0") or x0
            improved_graph, improved, y_imp, improved_judged = found.graph, found.improved, found.y, found.judged
        # a wrong first answer stalls the rounds (pairs.stall); round 1's fits in pairs may answer it
        # instead.  A round 2 whose graph location failed found nothing because it did not look
        stall = (pairs.stall(improved, floor, evidence.values())
                 if (len(rounds) == 2 and rounds[1].chosen is None and rounds[1].located and not fitted_pairs
                     and pairs.effect_count(chosen.candidate) == 1 and int(max_effects) >= 2) else None)
        paired = with_pairs(singles=stall.far) if stall else None
        if paired is not None and isinstance(paired[0].candidate, pairs.CandidatePair):
            paired[0].extra["stalled"] = str(chosen.candidate)
            paired[0].extra["stalled_why"] = stall.why
            chosen, alternatives = paired
            say("improved model", f"round 1 answered again, with {chosen.candidate}")
            improved_graph, improved, y_imp, improved_judged, x0, start = improved_model(chosen)
            rounds = [round_one(chosen, alternatives)]
        effects = [r.chosen for r in rounds if r.chosen is not None]
        if len(effects) >= 2:
            from .backfit import backfit

            def refit(base, cand, names, bounds, abandon_above):
                return fit_candidate(base, cand, round_part, held, uncertain=names, x0=round_x0, through=train,
                                     mid_run=False, judge=judge, start=own_start, bounds=bounds,
                                     abandon_above=abandon_above)

            def rechoose(reference, refits):        # the held-out part's choice alone, no training fallback
                return _choose(reference, refits, floor, None, None, exp, train, held, not_open_loop=True,
                               unstable=judge.unstable)[0]

            effects, backfitted = backfit(graph, rounds, fit=refit, floor=floor, choose=rechoose,
                                          with_values=_with_values, say=say, sensors=sensor_candidates,
                                          judge_model=lambda base: _holdout_nrmse(OutputSimulator(base, exp), None,
                                                                                  start_x0, judge)[0])
            if any(r.replaced is not None for r in rounds):
                improved_graph = backfitted
                x0 = next((e.extra["x0"] for e in reversed(effects) if e.extra.get("x0")), start_x0)
                improved, y_imp, improved_judged = _holdout_nrmse(OutputSimulator(improved_graph, exp), None, x0,
                                                                  judge)
                chosen = rounds[0].chosen
            say("joint refit", f"{len(effects)} effects")
            joint = _joint_refit(improved_graph, effects, exp, train, held, judge, x0, improved, floor,
                                 uncertain)
            rounds[-1].joint = joint
            if joint.kept:
                improved_graph, improved, y_imp, improved_judged = joint.graph, joint.improved, joint.y, joint.judged
        if int(max_effects) >= 2 and all(r.located for r in rounds[1:]):
            # the features' pair of kinds against the rounds' answer (pairs.rival_pairs, pairs.rival);
            # not where a further round's graph location failed: that round did not look
            effects = [r.chosen for r in rounds if r.chosen is not None]
            rivals = pairs.rival_pairs(fits, evidence.values(), [e.candidate for e in effects])
            if rivals:
                rival_fits, _ = fit_in_turn(rivals, fit_one, say, "fitting the features' pairs", best=best)
                fits.extend(rival_fits)
                joint = rounds[-1].joint
                n_answer = (joint.fit.n_params if joint is not None and joint.kept
                            else sum(e.n_params for e in effects))
                won = pairs.rival(rival_fits, improved, n_answer, nominal, floor)
                if won is not None:
                    won, why = won
                    won.extra["over_rounds"] = {"answer": " and ".join(str(e.candidate) for e in effects),
                                                "holdout_nrmse": dict(improved), "why": why}
                    chosen, alternatives = won, []
                    say("improved model", f"round 1 answered again, with {chosen.candidate}")
                    improved_graph, improved, y_imp, improved_judged, x0, start = improved_model(chosen)
                    rounds = [round_one(chosen, alternatives)]

    if chosen is not None and chosen.candidate is not None:
        _add_swapped_readings(rounds, improved_graph, train, x0, res.noise)
    from .diagnose_text import assemble
    return assemble(graph=graph, rec=rec, exp=exp, held=held, res=res, nominal=nominal,
                    improved=improved, y_imp=y_imp, windows=windows, rv=rv, scores=scores,
                    fits=fits, chosen=chosen, improved_graph=improved_graph,
                    locate_regime=locate_regime, timings=say.done, rounds=rounds, judge=judge,
                    judged=(nominal_judged, improved_judged), notes=spike_notes(exp, glitches))


def _restart(judge) -> int | None:
    """Under the segment judge, its segments' length in samples: the feature regression restarts
    there too (:mod:`diagnosis.feature_restarts`); None under the open-loop judge."""
    return judge.plan.length if judge.kind == "segments" and judge.plan is not None else None


def _features(graph, scores, places, train, x0, rv, cands, say, label, restart=None):
    """The feature regression at the junction places (:mod:`diagnosis.features`; `restart`, the
    segment length it restarts at, :func:`_restart`) and the candidates it leaves to fit:
    ``(evidence by place, candidates kept, candidates pruned)``."""
    from .features import feature_evidence, prune_candidates, with_feature_starts
    junctions = [p for p in places if p.kind in ("junction", "law")]
    if not junctions or not scores:       # no location (a diverging nominal): nothing to regress
        kept, pruned = prune_candidates(cands, {})      # only the kinds that need evidence go
        return {}, kept, [str(c) for c in pruned]
    say(label, ", ".join(map(str, junctions)))
    evidence = feature_evidence(graph, junctions, train, x0=x0, regime_variables=rv,
                                estimates={s.place: s.estimate for s in scores}, restart=restart)
    kept, pruned = prune_candidates(cands, evidence)
    return evidence, with_feature_starts(kept, evidence), [str(c) for c in pruned]


def _choose(reference, fits, floor, evidence, res, exp, train, held, not_open_loop, sim=None, open_loop=None,
            held_nominal=None, unstable=False):
    """:func:`~diagnosis.fit.choose` on the held-out part; when it answers "none" and the
    held-out part is judged open-loop (`not_open_loop` False: the nominal neither diverges nor
    drifts), the training part's answer among the fits the held-out part cannot judge
    (:mod:`diagnosis.training_judge`: fits whose held-out prediction is the reference's; `sim`,
    the reference model's OutputSimulator, tells an effect at the start from a wrong start state).
    Under the segment judge, `open_loop` (the reference's open-loop held-out NRMSE and the
    measurement noise floor) lets a fit that predicts the held-out part open-loop to about the
    noise answer instead of "none" (:mod:`diagnosis.open_loop_judge`), and `held_nominal` (the
    reference's held-out segment predictions, where its open-loop run over the training part
    stays finite and its mode does not grow e-fold within the held-out part: across tens of
    e-foldings an open-loop comparison is chance, and a chaotic Duffing oscillator's right model
    was answered with a backlash of 0.35 um) lets the training part answer among the fits whose
    segment predictions are the reference's: a drifting carriage's position sensor that clips at a
    level only the training part reaches (seed 3535, case 014, answered "none").  With `unstable`
    (the judge's nominal mode grows e-fold within the held-out part), the floor is not lowered to
    the best fit's held-out error (:func:`~diagnosis.fit.floor_within_reach`): across two
    e-foldings a fit's tiny change of the model reshuffles the restarts' noise, and on a chaotic
    Duffing oscillator without any effect a constant load of 0.0005 N lowered the segment error by
    12 %, under the replayed floor.

    Returns ``(chosen, alternatives)``: the fits of other kinds the held-out part cannot tell
    apart from a held-out choice (:func:`diagnosis.alternatives.indistinguishable`; none for an
    answer of the training part, which the held-out part cannot judge at all)."""
    from .alternatives import indistinguishable
    from .fit import choose, floor_within_reach, noise_floor
    from .residuals import nrmse
    from .training_judge import choose_on_training, mark_silent, restart_evidence
    if not fits:
        return None, []
    floor = floor if unstable else floor_within_reach(floor, fits, list(reference))
    n = train.t.size
    by_training = not not_open_loop or held_nominal is not None
    if by_training:
        mark_silent(fits, res.simulated, exp.outputs, res.noise, n, held_nominal=held_nominal)
    for f in fits:
        f.y = None
    chosen = choose(reference, fits, noise=floor, evidence=_lookup(evidence), measured=held.outputs)
    alternatives = indistinguishable(chosen, fits, reference, noise=floor, measured=held.outputs)
    if chosen is None and open_loop is not None:
        from .open_loop_judge import choose_open_loop
        chosen, alternatives = choose_open_loop(*open_loop, fits, evidence=_lookup(evidence), measured=held.outputs)
    for f in fits:
        for key in ("holdout_y", "open_loop_y"):     # read by the choice only
            f.extra.pop(key, None)
    if chosen is not None or not by_training:
        return chosen, alternatives
    nominal_train = {o: nrmse(train.outputs[o], res.simulated[o][:n]) for o in exp.outputs}

    def restart():
        return restart_evidence(sim, train, {o: res.simulated[o][:n] for o in exp.outputs}, res.noise)

    return choose_on_training(nominal_train, fits, floor=noise_floor(train, res.noise), n_train=n,
                              restart=restart if sim is not None else None), []


def _finite_over(y: dict, n: int) -> bool:
    """Whether every output of `y` is finite over its first `n` samples."""
    return all(np.all(np.isfinite(np.asarray(v[:n], float))) for v in y.values())


def _lookup(evidence):
    from .features import evidence_lookup
    return evidence_lookup(evidence) if evidence else None


def _companion_fits(graph, fits, places, train, rv, fit, say, label, best, x0=None) -> list:
    """Fits at the law places acting on a located junction (:mod:`diagnosis.place_choice`'s
    companions) of the kinds that fitted best at that junction."""
    from .catalogue import candidates
    from .fit_in_turn import fit_in_turn
    from .place_choice import companion_candidates

    laws_at = companions(graph, places)
    if not laws_at:
        return []
    cands = companion_candidates(fits, laws_at, lambda place: candidates(graph, place, regime_variables=rv,
                                                                           experiment=train, x0=x0))
    return fit_in_turn(cands, fit, say, label, best=best, suffix=", laws")[0]


def _twin_fits(graph, fits, train, rv, fit, say, label, best, x0=None, n_places: int = 3) -> list:
    """Fits of the same kind at all twins of the best single-place fits' places
    (:mod:`diagnosis.twins`): an effect on every copy of a repeated component.  `fit` is
    ``fit(candidate, abandon_above)``; `best` the single-place fits' best training cost
    (:func:`diagnosis.fit_in_turn.fit_in_turn`); `x0` the recording's initial state.  As many
    groups as places were fitted (`n_places`, 3 to 6): the tied and actuator places that join the
    located ones must not crowd out the twins of another place's best kind.  A group's members that
    end idle are dropped from its answer (:func:`diagnosis.twins.without_idle_members`)."""
    from .catalogue import candidates
    from .fit_in_turn import fit_in_turn
    from .graph_location import candidate_places
    from .twins import twin_groups, without_idle_members

    groups = twin_groups(graph, fits, candidate_places(graph, experiment=train),
                         lambda place: candidates(graph, place, regime_variables=rv, experiment=train, x0=x0),
                         experiment=train, best=min(max(int(n_places), 3), 6))
    fitted = fit_in_turn(groups, fit, say, label, best=best, suffix=", twins")[0]
    return [without_idle_members(f, graph) for f in fitted]


def _further_round(graph, exp, train, held, judge, x0, reference, floor, rounds, *, top, say, label, start=None):
    """One more effect on `graph` (the improved graph so far) against its own residual.

    Location, candidates at the ``top`` places (minus the kinds already added at
    the same place) and the sensors at every output where something was located, fits with the
    earlier effects' values fixed in the graph, and :func:`~diagnosis.fit.choose` against
    `reference` (the held-out NRMSE of `graph`) with the noise floor `floor`.  Returns a
    :class:`~diagnosis.rounds.Round`: ``chosen`` (CandidateFit or None), ``fits``, ``reference``,
    ``improved``, ``scores`` and, when something was kept, ``graph`` and ``y`` (its simulated
    outputs).  `start`: as :func:`~diagnosis.fit.fit_candidate`'s, where the recording's start
    state was estimated.
    """
    from .catalogue import candidates
    from .fit import fit_candidate
    from .fit_in_turn import fit_in_turn
    from .graph_location import locate_on_graph
    from .locate import regime_variables
    from .residuals import OutputSimulator, residuals

    from .errors import SimulationError

    say(f"{label}: residual of the improved model")
    sim = OutputSimulator(graph, exp)
    try:
        res = residuals(graph, exp, simulator=sim, x0=x0)
    except SimulationError as exc:      # judged by segments, the improved model may still diverge
        return Round(None, [], dict(reference), dict(reference), scores=[],
                     note=f"the improved model diverges open-loop ({exc}): no run to locate along")
    rv = {k: (v[:train.t.size], d) for k, (v, d) in regime_variables(graph, exp, res.run).items()}
    say(f"{label}: graph location", "training part")
    try:
        scores = locate_on_graph(graph, train, x0=x0)
    except (np.linalg.LinAlgError, FloatingPointError, SimulationError) as exc:   # numerics: no further effect
        # (a loop an earlier effect closed may fail at a probe's perturbed state: the round did
        # not look, and the effects found so far stand)
        return Round(None, [], dict(reference), dict(reference), scores=[], located=False,
                     note=f"graph location failed: {type(exc).__name__}: {exc}")
    places, springs, sensors = further_places(graph, scores, top, train)
    earlier = [c for r in rounds if r.chosen is not None and r.chosen.candidate is not None
               for c in getattr(r.chosen.candidate, "members", (r.chosen.candidate,))]
    done = {(c.kind, c.place) for c in earlier}
    # nor is a parameter an earlier round fitted fitted again, nor an element's law it rewrote
    # rewritten again (pairs.clashes): a spring's value refitted in round 1 and refitted with a
    # cubic term in round 2 answered the rest of round 1's fit as a cubic spring (a detuned
    # hydraulic null, oil volume C2)
    claimed = pairs.claims(earlier)
    cands = [c for s in places for c in candidates(graph, s.place, regime_variables=rv, experiment=train, x0=x0)
             if (c.kind, c.place) not in done and not pairs.clashes(c, claimed)
             and (s not in springs or on_storage(graph, c)) and (s not in sensors or c.definition.unranked_sensor)]
    evidence, cands, pruned = _features(graph, scores, [s.place for s in places], train, x0, rv, cands, say,
                                        f"{label}: feature regression", restart=_restart(judge))
    fit_part, fit_x0 = _fit_window(train, res.run, x0)

    def fit_one(cand, abandon_above):
        return fit_candidate(graph, cand, fit_part, held, x0=fit_x0, through=train, mid_run=False,
                             abandon_above=abandon_above, judge=judge, start=start)

    fits, best = fit_in_turn(cands, fit_one, say, f"{label}: fitting")
    fits += _companion_fits(graph, fits, [s.place for s in places], train, rv, fit_one, say, f"{label}: fitting",
                            best, x0)
    fits += _twin_fits(graph, fits, train, rv, fit_one, say, f"{label}: fitting", best, x0, len(places))
    say(f"{label}: choosing")
    chosen, alternatives = _choose(reference, fits, floor, evidence, res, exp, train, held, judge.kind != "open-loop",
                                   sim, unstable=judge.unstable)
    out = Round(chosen, fits, dict(reference), dict(reference), scores=scores, features=list(evidence.values()),
                pruned=pruned, indistinguishable=alternatives + unexcited(graph, chosen, train, x0))
    if chosen is not None:
        names = {p.name for p in chosen.candidate.params}
        better = chosen.candidate.build(graph, {k: v for k, v in chosen.values.items() if k in names})
        out.improved, out.y, out.judged = _holdout_nrmse(OutputSimulator(better, exp), None,
                                                         chosen.extra.get("x0") or x0, judge)
        out.graph = better
    return out


def _add_swapped_readings(rounds, graph, train, x0, noise) -> None:
    """Each round's answer with the one-parameter twins it reads as on the fits' window
    (:func:`diagnosis.equivalent_readings.swapped_readings`), after its fitted alternatives."""
    from .equivalent_readings import swapped_readings
    answered = [r for r in rounds if r.chosen is not None and r.chosen.candidate is not None]
    part, part_x0 = _fit_window(train, None, x0)
    found = swapped_readings(graph, [r.chosen.candidate for r in answered], part, part_x0, noise)
    for i, twins in found.items():
        r = answered[i]
        listed = {(a.kind, a.place) for a in r.indistinguishable or ()}
        r.indistinguishable = list(r.indistinguishable or ()) + [a for a in twins if (a.kind, a.place) not in listed]


def _joint_refit(graph, effects, exp, train, held, judge, x0, reference, floor, uncertain):
    """All accepted effects' parameters (and the `uncertain` ones) refitted together on the
    training part of `graph` (the improved graph), started from their round-by-round values.

    Returns a :class:`~diagnosis.rounds.JointRefit`: ``fit`` (CandidateFit), ``reference`` and
    ``improved`` held-out NRMSE (by the diagnosis's held-out judge, as for every round), ``kept`` (the
    held-out excess error beyond the noise floor did not grow), ``graph`` and ``y`` of the
    refitted model.
    """
    from .fit import excess_error, fit_candidate
    from .residuals import OutputSimulator

    from .backfit import refittable
    names, own = refittable(graph, effects)       # a released saturation limit stays released
    names += list(uncertain)
    part, part_x0 = _fit_window(train, None, x0)
    fit = fit_candidate(graph, None, part, held, uncertain=names, x0=part_x0, through=train, judge=judge,
                        within=own)
    out = JointRefit(fit, dict(reference), dict(reference))
    if not all(np.isfinite(v) for v in fit.values.values()) or not np.all(np.isfinite(
            list(fit.holdout_nrmse.values()))):
        return out
    better = _with_values(graph, fit.values)
    improved, y, judged = _holdout_nrmse(OutputSimulator(better, exp), None, x0, judge)
    outputs = list(reference)
    kept = excess_error(improved, floor, outputs) <= excess_error(reference, floor, outputs)
    out.improved, out.kept, out.graph, out.y, out.judged = improved, kept, better, y, judged
    return out
