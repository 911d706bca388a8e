"""Assembling a :class:`~diagnosis.report.DiagnosisReport` from the pipeline's results:
location, missing physics, before/after numbers, plain-language explanation."""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from .pairs import CandidatePair, effect_count
from .report import DiagnosisReport, PlotData

__all__ = ["assemble"]

#: a regime variable must explain this share of the located correction to be named
_MIN_REGIME_SHARE = 0.1


def _pct(nominal, improved):
    return f"{100 * (1 - improved / nominal):.0f} %" if nominal > 0 else "n/a"


def _regime(chosen, scores, res, n_train, rv, locate_regime, units):
    """The regime of the chosen place's correction (a junction's estimated extra
    effort/flow), else of the residual of the worst output; training part."""
    place = chosen.candidate.place if chosen is not None and chosen.candidate is not None else None
    score = next((s for s in scores if place is not None and s.place == place), None)
    if score is not None and place.kind in ("junction", "law"):
        signal, unit = np.asarray(score.estimate, dtype=float)[:n_train], score.unit
        label = f"located extra {'effort' if unit else 'correction'} at {place.name} ({unit})"
    else:
        worst = max(res.nrmse, key=res.nrmse.get)
        signal, unit = res.residual[worst][:n_train], units.get(worst, "")
        label = f"residual of {worst}"
    if signal.size != n_train or not rv:
        return None, None, None, ""
    seen = np.isfinite(signal)          # a correction estimated on a window of the record
    if not seen.all():
        signal, rv = signal[seen], {k: (np.asarray(v)[seen], d) for k, (v, d) in rv.items()}
    finding = locate_regime(signal, rv, unit=unit)
    if finding.explained < _MIN_REGIME_SHARE:
        finding = replace(finding, description=(
            f"everywhere: no operating regime explains it (best {finding.feature} of "
            f"{finding.variable}, {100 * finding.explained:.0f} %)"))
    values = rv[finding.variable][0] if finding.variable else None
    return finding, values, signal, label


def _effects(fit, refit=None, alternatives=None) -> list[dict]:
    """The ``missing_physics`` entries of an accepted candidate fit, one per place (a group of
    twins gives one per member; values of a kept joint refit, dict name -> value, replace the
    round's); each with its round's `alternatives` (:class:`~diagnosis.alternatives.Alternative`)
    as ``indistinguishable``."""
    values = {**fit.values, **(refit or {})}
    out = []
    for cand in getattr(fit.candidate, "members", (fit.candidate,)):
        names = {p.name for p in cand.params}
        params = {k: float(v) for k, v in values.items() if k in names}
        out.append({"kind": cand.kind, "attached_to": str(cand.place), "parameters": params,
                    "explanation": cand.explain(params), "judged_on": fit.extra.get("judge", "held-out"),
                    "indistinguishable": [a.to_json() for a in alternatives or ()]})
    return out


def _named(found) -> str:
    """The ``missing_physics`` entries `found` of one round in words: one kind at its places (a
    group of twins), or each kind at its place (a pair)."""
    if len({m["kind"] for m in found}) == 1:
        return f"{found[0]['kind']} at {', '.join(m['attached_to'] for m in found)}"
    return " and ".join(f"{m['kind']} at {m['attached_to']}" for m in found)


def _indistinguishable_text(winner, alternatives) -> list[str]:
    """One sentence naming the readings the recording cannot tell apart from `winner`
    (:mod:`diagnosis.alternatives`), with their held-out NRMSE against the winner's, z and the
    largest difference of the two held-out predictions in noise standard deviations."""
    if not alternatives:
        return []

    def one(a):
        where = f" at {a.place}" if a.place else " (the nominal parameters refitted alone)"
        if a.unexcited:
            return f"{a.kind}{where} (not fitted: {a.unexcited}; on this record it is the answer's law)"
        if a.structural:
            return f"{a.kind}{where} (not fitted: {a.structural})"
        errors = ", ".join(f"{o} {v:.3g} vs {winner.holdout_nrmse[o]:.3g}" for o, v in a.holdout_nrmse.items()
                           if o in winner.holdout_nrmse)
        z = f"z = {a.z:.1f}" if np.isfinite(a.z) else "z not computable"
        gap = (f"; the held-out predictions differ by at most {a.difference:.2g} noise standard deviations"
               if np.isfinite(a.difference) else "")
        return f"{a.kind}{where} (held-out NRMSE {errors}; {z}{gap})"
    fitted = any(not (a.unexcited or a.structural) for a in alternatives)
    why = (" The answer above has the lower priced held-out error or won the choice rule's ties (fewer parameters, "
           "the plainer place, the training error, the catalogue's order)." if fitted else "")
    return [f"Not told apart by this recording: {'; '.join(one(a) for a in alternatives)}.{why}"]


def _judged_on_training(fit) -> str:
    """Why an effect was accepted on the training part (:mod:`diagnosis.training_judge`)."""
    return (f"Judged on the training part: the held-out part never reaches the regime where this effect "
            f"acts (its prediction there differs from the model's by "
            f"{fit.extra.get('holdout_change', 0.0):.2g} noise standard deviations), so the held-out error "
            f"can neither confirm nor refute it; on the training part it explains "
            f"{100 * fit.extra.get('train_share', 0.0):.0f} % of the error beyond the noise.")


def _judged_open_loop(fit) -> str:
    """Why an effect the segment judge found within its floor was accepted
    (:mod:`diagnosis.open_loop_judge`)."""
    reading = ", ".join(f"{o} {v:.3g}" for o, v in fit.extra.get("open_loop_reading", {}).items())
    return ("Judged open-loop: the segment error's restarts carry the noise of their estimated states, and "
            "within that floor it is not told from the nominal; but simulated open-loop from the recording's "
            f"start, the model with it predicts the held-out part to about the measurement noise "
            f"(NRMSE {reading}), where the nominal drifts.")


def _unseen_by_fits(windows, t, holdout_start: float) -> str:
    """Why nothing was fitted when the residual exceeds the noise only in the held-out part, which
    location and the fits never see (a sensor's range reached only there), and the holdout that
    puts the first such window in the training part; else ""."""
    if not windows or any(a < holdout_start for a, _ in windows):
        return ""
    a, b = windows[0]
    fraction = np.floor(100 * (t[-1] - b) / (t[-1] - t[0])) / 100
    hint = (f"; a holdout of {fraction:.2f} or less (--holdout) puts its first window, {a:.4g}-{b:.4g} s, "
            f"in the training part" if fraction >= 0.01 else "")
    return (f"the residual exceeds the noise only in the held-out part (from {holdout_start:.4g} s), which "
            f"location and the fits do not see{hint}")


def assemble(*, graph, rec, exp, held, res, nominal, improved, y_imp, windows, rv, scores, fits,
             chosen, improved_graph, locate_regime, timings, rounds=(), judge=None,
             judged=(None, None), notes=()) -> DiagnosisReport:
    """Build the report (see :func:`diagnosis.diagnose.diagnose` for the arguments' meaning;
    `rounds`: one :class:`~diagnosis.rounds.Round` per round; `judge`: the held-out
    :class:`~diagnosis.segments.Judge`, `judged`: the nominal and the improved model judged by it;
    `notes`: notes on the recording beyond its own, such as the spikes replaced)."""
    notes = rec.notes() + list(notes)
    n_train = exp.t.size - held.t.size
    units = dict(exp.units)
    finding, regime_values, regime_signal, regime_label = (None, None, None, "")
    if chosen is not None and chosen.candidate is not None:
        finding, regime_values, regime_signal, regime_label = _regime(chosen, scores, res, n_train, rv,
                                                                      locate_regime, units)
        place = chosen.candidate.place
        attached = place.name if place.kind == "junction" else str(place)
        joint = next((r.joint for r in rounds if r.joint is not None), None)
        refit = joint.fit.values if joint is not None and joint.kept else None
        physics = _effects(chosen, refit, rounds[0].indistinguishable if rounds else None)
        physics += [e for r in list(rounds)[1:] if r.chosen is not None
                    for e in _effects(r.chosen, refit, r.indistinguishable)]
        location = {"junction": attached, "bond": place.bond or "",
                    "windows": windows, "regime": finding.description if finding else ""}
    else:
        refit = {k: float(v) for k, v in chosen.values.items()} if chosen is not None else {}
        why = (_why_none(nominal, fits, rounds) if fits
               else _unseen_by_fits(windows, exp.t, float(held.t[0])) or
               "no place on the graph explains a significant share of the residual")
        if refit:
            why = "no missing physics; the uncertain nominal parameters were refitted"
        physics = [{"kind": "none", "attached_to": "", "parameters": refit, "explanation": why}]
        location = {"junction": "", "bond": "", "windows": windows, "regime": ""}
    if rounds and rounds[0].restarted:
        location["restarted"] = [{"place": str(s.place), "explained": float(s.explained)} for s in rounds[0].restarted]
    fit = {"holdout": [float(held.t[0]), float(held.t[-1])], "nominal": nominal, "improved": improved,
           "substeps": int(exp.substeps)}
    if rounds and rounds[0].window is not None:
        fit.update(window=rounds[0].window, start=rounds[0].start)
    if judge is not None:
        fit.update(judge.to_json())
        if judged[0] is not None and judged[1] is not None:
            fit["open_loop"] = {"nominal": dict(judged[0].open_loop), "improved": dict(judged[1].open_loop)}
    text = _text(rec, exp, held, res, nominal, improved, windows, scores, fits, chosen, physics,
                 finding, rounds, judge, judged, notes)
    plot = PlotData(exp.t, dict(exp.outputs), dict(res.run.outputs), dict(y_imp), units,
                    float(held.t[0]), finding.variable if finding else None, regime_values,
                    regime_signal, regime_label)
    if judge is not None and judge.kind == "segments" and judged[0] is not None and judged[1] is not None:
        plot.judge = "segments"
        plot.segment_starts = [float(held.t[a]) for a in judge.plan.starts]
        plot.nominal_segments, plot.improved_segments = dict(judged[0].segments), dict(judged[1].segments)
    report = DiagnosisReport(location, physics, fit, text, improved_graph, None, scores, fits, chosen,
                             notes, timings(), plot, rounds=list(rounds))
    for i, r in enumerate(report.rounds, 1):
        report.timings[f"round {i}"] = r.seconds
    return report


def _why_none(nominal, fits, rounds) -> str:
    """Which rule of :func:`diagnosis.fit.choose` answered none, with the numbers."""
    from .fit import MIN_GAIN, MIN_SHARE, acceptance, needs_explaining, usable_fits
    floor = (rounds[0].floor if rounds else None) or {}
    if not needs_explaining(nominal, floor):
        return "the nominal model's held-out error stays within the measurement noise"
    usable = usable_fits(fits, list(nominal))
    if not usable:
        return f"none of the {len(fits)} candidate fits succeeded"
    best = max(usable, key=lambda f: acceptance(nominal, f, floor)[0])
    share, gain = acceptance(nominal, best, floor)
    return (f"the best candidate ({best.candidate or 'nominal refit'}) explains {100 * share:.0f} % of the "
            f"held-out error beyond the noise and lowers its NRMSE by {100 * gain:.0f} % (at least "
            f"{100 * MIN_SHARE:.0f} % and {100 * MIN_GAIN:.0f} % are required)")


def _judge_lines(judge, judged, outputs) -> list[str]:
    """How the held-out part was judged, and why."""
    if judge is None:
        return []
    if judge.kind != "segments":
        return [f"Held-out judge: open-loop simulation ({judge.reason})."]
    p = judge.plan
    lines = [f"Held-out judge: segment simulation error, because {judge.reason}. The held-out part is cut "
             f"into {len(p.starts)} segments of {p.seconds:.3g} s ({p.length} samples); each restarts from a "
             f"state estimated on its first {p.estimation} samples and is scored on the rest. Every "
             f"held-out NRMSE below is this segment error."]
    nominal, improved = judged
    if nominal is not None and improved is not None:
        lines.append("Open-loop held-out NRMSE, for reference: " + ", ".join(
            f"{o} {nominal.open_loop[o]:.3g} -> {improved.open_loop[o]:.3g}" for o in outputs) + ".")
    return lines


def _text(rec, exp, held, res, nominal, improved, windows, scores, fits, chosen, physics, finding,
          rounds=(), judge=None, judged=(None, None), notes=()):
    u = exp.units
    lines = [f"Recording {rec.source}: {exp.t.size} samples over {exp.span[0]:.4g}-{exp.span[1]:.4g} s; "
             f"held out {held.span[0]:.4g}-{held.span[1]:.4g} s."]
    lines += [f"Note: {n}." for n in notes]
    for o in exp.outputs:
        lines.append(f"Output {o}: nominal held-out NRMSE {nominal[o]:.3g} (noise about "
                     f"{res.noise[o]:.3g} {u.get(o, '')}).")
    lines += _judge_lines(judge, judged, list(exp.outputs))
    if exp.substeps > 1:
        lines.append(f"Integration: at least {exp.substeps} RK4 sub-steps per sample interval in every simulation: "
                     "with half as many, the nominal's outputs moved by more than a tenth of their noise "
                     "(diagnosis.residuals.settle_substeps).")
    diverged = rounds[0].diverged if rounds else ""
    if diverged:
        where = ("the places were located on windows of the training part restarted from states "
                 "estimated from the data" if scores else
                 "with no run to locate along, the candidates of every place were fitted")
        lines.append(f"The nominal model diverges on this recording ({diverged}). That is evidence of missing "
                     f"physics, not an error: {where}" + (", and each model is judged by its segment error."
                                                          if judge is not None and judge.kind == "segments" else
                                                          ", and the nominal held-out error counts as unbounded."))
    elif windows:
        shown = ", ".join(f"{a:.3g}-{b:.3g} s" for a, b in windows[:6])
        more = f" and {len(windows) - 6} more" if len(windows) > 6 else ""
        lines.append(f"The residual exceeds the noise in {len(windows)} window(s): {shown}{more}.")
    else:
        lines.append("The residual stays within the measurement noise everywhere.")
    if scores:
        best = ", ".join(f"{s.place} {100 * s.explained:.0f} %" for s in scores[:3])
        lines.append(f"Share of the residual a correction explains, by place: {best}.")
    if rounds and rounds[0].restarted and judge is not None:
        best = ", ".join(f"{s.place} {100 * s.explained:.0f} %" for s in rounds[0].restarted[:3])
        lines.append(f"On windows of the training part restarted every {judge.plan.seconds:.3g} s from states "
                     f"fitted to the data (the nominal drifts; diagnosis.graph_location_segments): {best}; "
                     "candidates are fitted at these places too.")
    for ev in (rounds[0].features or []) if rounds else []:
        lines.append(f"Feature regression at {ev.place} (validated share of the residual beyond the noise "
                     f"each kind's features explain): {ev.summary()}.")
    if rounds and rounds[0].pruned:
        lines.append(f"Not fitted, the features explaining far less than the best kind's: "
                     f"{', '.join(rounds[0].pruned)}.")
    if fits and rounds and rounds[0].window is not None:
        a, b = rounds[0].window
        lines.append(f"Candidates were fitted on {a:.4g}-{b:.4g} s of the training part, simulated from "
                     f"{rounds[0].start}.")
    m = physics[0]
    if m["kind"] == "none":
        lines.append(f"Missing physics: none - {m['explanation']} "
                     f"({len(fits)} candidate fit(s) tried).")
    else:
        first = physics[:len(getattr(chosen.candidate, "members", (None,)))]   # round 1: one per twin place
        heading = "Wrong nominal value" if all(e["kind"] == "nominal_value" for e in first) else "Missing physics"
        lines.append(f"{heading}: {_named(first)}. {'; '.join(e['explanation'] for e in first)}")
        if isinstance(chosen.candidate, CandidatePair) and chosen.extra.get("stalled"):
            lines.append(f"Round 1 first answered {chosen.extra['stalled']}, on whose model nothing more was found "
                         f"while {chosen.extra['stalled_why']}; these two, fitted together (diagnosis.pairs), explain it instead.")
        elif isinstance(chosen.candidate, CandidatePair) and chosen.extra.get("over_rounds"):
            over = chosen.extra["over_rounds"]
            held = ", ".join(f"{o} {v:.3g} -> {chosen.holdout_nrmse[o]:.3g}"
                             for o, v in over["holdout_nrmse"].items() if o in chosen.holdout_nrmse)
            lines.append(f"The rounds, one effect at a time, first answered {over['answer']}; round 1's feature "
                         f"regression had selected these two together, and fitted together they predict the "
                         f"held-out part {over['why']} (held-out NRMSE {held}; diagnosis.pairs.rival).")
        elif isinstance(chosen.candidate, CandidatePair) and effect_count(chosen.candidate) == 1:
            lines.append("The effect was fitted with the nominal value beside it (diagnosis.pairs.value_pairs).")
        elif isinstance(chosen.candidate, CandidatePair):
            lines.append("No single candidate explained the required share of the residual; these two were "
                         "fitted together (diagnosis.pairs).")
        if chosen.extra.get("judge") == "training":
            lines.append(_judged_on_training(chosen))
        if chosen.extra.get("judge") == "open-loop":
            lines.append(_judged_open_loop(chosen))
        if chosen.extra.get("resolved_over"):
            other, z = chosen.extra["resolved_over"]
            lines.append(f"{other}, with fewer parameters, tied it or won on the parameters' price; the "
                         f"held-out part resolves this fit's lower error (z = {z:.1f}, diagnosis.holdout_resolution).")
        if chosen.extra.get("preferred_over"):
            lines.append(f"Held-out error nearly tied it with {chosen.extra['preferred_over']}; the feature "
                         f"regression decided.")
        lines += _indistinguishable_text(chosen, rounds[0].indistinguishable if rounds else None)
        lines += _backfit_text(1, rounds[0]) if rounds else []
        if finding is not None and finding.variable is not None:
            share = ("" if finding.explained < _MIN_REGIME_SHARE
                     else f" (explains {100 * finding.explained:.0f} % of it)")
            lines.append(f"Operating regime: {finding.description}{share}.")
        others = sorted((f for f in fits if str(f.candidate) != str(chosen.candidate) and f.success
                         and f.holdout_nrmse),
                        key=lambda f: sum(f.holdout_nrmse.values()))[:3]
        if others:
            lines.append("Runners-up (held-out NRMSE): " + "; ".join(
                f"{f.candidate or 'nominal refit'} "
                + ", ".join(f"{o} {v:.3g}" for o, v in f.holdout_nrmse.items()) for f in others) + ".")
    given_up = sum(1 for f in fits if f.extra.get("abandoned"))
    if given_up:
        lines.append(f"{given_up} of {len(fits)} fits were given up early: their training error stayed "
                     f"far above the best fit's (diagnosis.fit_in_turn).")
    lines += _further_text(list(rounds)[1:], exp.outputs)
    for o in exp.outputs:
        lines.append(f"Held-out NRMSE of {o}: nominal {nominal[o]:.3g} -> improved {improved[o]:.3g} "
                     f"({_pct(nominal[o], improved[o])} lower).")
    return "\n".join(lines)


def _backfit_text(number: int, r) -> list:
    """A line on round `number`'s effect replaced by backfitting (:mod:`diagnosis.backfit`)."""
    if r.replaced is None:
        return []
    old = next((f for f in r.backfit or () if str(f.candidate) == str(r.replaced.candidate) and f.success), None)
    held = ""
    if old is not None:
        held = " (held-out NRMSE " + ", ".join(f"{o} {old.holdout_nrmse[o]:.3g} -> {v:.3g}"
                                                for o, v in r.chosen.holdout_nrmse.items()) + ")"
    return [f"Backfitted: with the other effects in place, round {number}'s candidates were fitted again; "
            f"{r.chosen.candidate} now fits the held-out part better than {r.replaced.candidate}, "
            f"which round {number} chose first{held} (diagnosis.backfit)."]


def _further_text(rounds, outputs):
    """Lines for rounds 2, 3, ...: each further effect, or why nothing more was added."""
    lines = []
    for i, r in enumerate(rounds, 2):
        c = r.chosen
        if c is None and r.note:
            lines.append(f"Round {i}: nothing more - {r.note}.")
            continue
        if c is None and not r.fits:
            lines.append(f"Round {i}: nothing more - no place on the improved graph explains a "
                         f"significant share of what is left of the residual.")
            continue
        if c is None:
            lines.append(f"Round {i}: nothing more - no further candidate improves the held-out error "
                         f"beyond the noise and the price of its parameters ({len(r.fits)} tried).")
            continue
        found = _effects(c)
        gain = ", ".join(f"{o} {r.reference[o]:.3g} -> {r.improved[o]:.3g}" for o in outputs)
        lines.append(f"Also missing (round {i}): {_named(found)}. "
                     f"{'; '.join(m['explanation'] for m in found)} (held-out NRMSE {gain}).")
        if c.extra.get("judge") == "training":
            lines.append(_judged_on_training(c))
        lines += _indistinguishable_text(c, r.indistinguishable)
        lines += _backfit_text(i, r)
    joint = next((r.joint for r in rounds if r.joint is not None), None)
    if joint is not None:
        gain = ", ".join(f"{o} {joint.reference[o]:.3g} -> {joint.improved[o]:.3g}" for o in outputs)
        verdict = ("kept; the values above are the joint ones" if joint.kept
                   else "not kept: it does not lower the held-out error")
        lines.append(f"Joint refit of all effects' parameters on the training part: held-out NRMSE "
                     f"{gain} ({verdict}).")
    return lines
