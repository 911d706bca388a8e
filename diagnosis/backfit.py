"""Backfitting: each effect chosen again with the other effects in place.

A round chooses its effect on a model that still lacks the effects later rounds find, and a later
round on an earlier effect fitted without it.  Where one effect accounts for part of the residual
another was chosen to explain, that choice was made on the wrong residual: a transport delay in a
pump's flow, seen through a pipe that also lacks its viscous loss, fits better as a first-order lag
(the lag's phase stands in for some of the missing damping); a Coulomb + viscous friction on a mass
whose spring also has backlash loses its Coulomb part to the dead band; a carriage's constant load,
looked for after a force lag fitted without it (0.20 s where 0.14 s is right), fits worse than a
viscous friction.  With the other effects in place, and their parameters free to move, each
round's own candidates tell the delay from the lag, the Coulomb + viscous law from the viscous one,
the load from the friction.

So once several effects were found, each round's best few candidates (:data:`ALTERNATIVES` kinds
or places, the chosen one first, ranked by the round's held-out error) are fitted again on the
nominal model with every other effect built in, each started from where it ended; the other
effects' parameters are refitted alongside within their kinds' bounds (fitted beside the effect now
taken out, they may have to move far: a leak answered at the wrong tank had left the right tank's
leak at a third of its size) and not priced (the reference has them too); the sensor candidates at
the outputs the round's effect leaves unexplained are fitted with them (a sensor's error is what a
larger residual hides from graph location).  The round's own rule (:func:`diagnosis.fit.choose`)
chooses among them against that model's held-out error.  A different winner replaces the effect
(the round keeps the one it replaced, ``Round.replaced``, and the refits, ``Round.backfit``); no
winner leaves it as it was, and neither does a winner whose held-out error the round's own refit
ties (:func:`diagnosis.fit.within_tie`) with as many parameters or fewer: between two readings the
recording does not tell apart, a swap is named by tie-breakers only, and it moves what the later
rounds were fitted beside (a carriage's force gain swapped on a tie for a gain of its velocity
sensor left the next round's refits no sensor to find that sensor's offset at).
The rounds are swept in order, and once more up to the last one the first sweep replaced
(:data:`SWEEPS`): those before it were chosen beside the effect it replaced.  This is the
backfitting of additive models (Hastie and Tibshirani, *Generalized Additive Models*, 1990, ch.
4), over kinds instead of smooth functions; the joint refit of all effects' parameters follows it
(:func:`diagnosis.diagnose._joint_refit`).
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from .errors import BondcosimError, DiagnosisError
from .fit import harms, needs_explaining, unpriced_error, usable_fits, within_tie
from .fit_in_turn import HOPELESS, train_cost
from .kinds.base import extends
from .pairs import claims, clashes, effect_count

__all__ = ["ALTERNATIVES", "SWEEPS", "alternatives", "backfit", "build_effects", "refittable", "placed_in"]

#: the round's candidates fitted again: its chosen kind and the next best, by held-out error
#: (seed 3434, compound case 028: the right kind was the sixth of its round)
ALTERNATIVES = 6
#: a richer law whose held-out error (unpriced) is at least this share of that of a simpler law it
#: extends did no better: it takes no slot among the `ALTERNATIVES` (a direction-dependent viscous
#: friction on a carriage that rarely reversed, equal to the viscous one, pushed a constant load,
#: the sixth, out of them: compound seed 3434, case 028)
IDLE_EXTENSION = 0.98
#: sweeps over the rounds at most: a second one over the rounds before the last effect the first
#: replaced, which were chosen again beside the effect it replaced (a carriage's mass refitted
#: beside a force lag kept a constant load the input delay that replaced the lag left idle:
#: detuned benchmark, seed 7474, case 024)
SWEEPS = 2


def build_effects(graph, effects, with_values):
    """`graph` with each of `effects` (CandidateFits, in order) built in at its fitted values; the
    values of parameters that are not the candidate's own (refitted nominal ones) set by
    ``with_values(graph, values)``.  An effect at a junction `graph` lacks (one an effect left out
    made: :func:`placed_in`) is a :class:`~diagnosis.errors.DiagnosisError`."""
    for effect in effects:
        if not placed_in(graph, effect.candidate):
            raise DiagnosisError(f"{effect.candidate} sits at a junction that an effect left out made")
        own = {p.name for p in effect.candidate.params}
        graph = effect.candidate.build(graph, {k: v for k, v in effect.values.items() if k in own})
        graph = with_values(graph, {k: v for k, v in effect.values.items() if k not in own})
    return graph


def alternatives(chosen, fits, reference: dict, floor: dict, n: int = ALTERNATIVES, taken=frozenset(),
                 changed=frozenset()) -> list:
    """The round's chosen fit and the successful fits of the next best kinds or places (one fit per
    kind and place, lowest held-out error on the outputs that needed explaining first, none that
    predicts an output worse than `reference`, :func:`~diagnosis.fit.harms`), at most
    `n` in all, the chosen first; none with a parameter named in `taken` or rewriting an element
    in `changed` (the other effects' claims: :func:`~diagnosis.pairs.clashes`), and none adding another
    number of effects than the chosen one (:func:`~diagnosis.pairs.effect_count`): a round's pairs
    must not make a single effect two, beyond the diagnosis' ``max_effects`` (with pairs fitted
    after every first answer, the cylinder rig's recording answered three), nor a pair one.

    Each pair's members alone that count as many effects follow it, beyond the `n`: a value pair
    (:func:`~diagnosis.pairs.value_pairs`) whose effect ends idle beside a later round's effect is
    its value alone (the detuned benchmark's carriage with an input delay and its mass 5 % off,
    seed 7474, case 024: a constant load of 5e-5 N was answered beside the mass)."""
    significant = needs_explaining(reference, floor) or list(reference)
    # a fit that predicts an output worse than the round's reference is no alternative
    # (fit.harms): ranked by the outputs that needed explaining alone, a velocity sensor's lag that
    # doubled a carriage's position error took the slot of its mass's value (seed 7474, case 024)
    ranked = sorted((f for f in usable_fits(fits, list(reference)) if not harms(f, reference, floor)),
                    key=lambda f: unpriced_error(f, significant))
    count = effect_count(chosen.candidate)

    def allowed(fit):
        return (fit.candidate is not None and _key(fit) not in seen and effect_count(fit.candidate) == count
                and not clashes(fit.candidate, (taken, changed)))

    def extended(fit):
        """The fit of a simpler law `fit` extends and does no better than, or None."""
        error = unpriced_error(fit, significant)
        return next((g for g in ranked if extends(fit.candidate, g.candidate)
                     and error >= IDLE_EXTENSION * unpriced_error(g, significant)), None)

    out, seen, picked, deferred = [], set(), 0, []
    for fit in [chosen] + ranked:
        simpler = extended(fit) if fit is not chosen else None
        if simpler is not None:
            deferred.append((fit, simpler))
            continue
        if picked < n and allowed(fit):
            picked += 1
            members = {str(m) for m in getattr(fit.candidate, "members", ())}
            for f in [fit] + [f for f in ranked if str(f.candidate) in members]:
                if allowed(f):
                    out.append(f)
                    seen.add(_key(f))
    # a richer law that did no better than the simpler one it extends takes no slot of its own: it
    # follows that one, beyond the `n` (fitted again beside the other effects, its extra term may
    # then act: a Coulomb + viscous law that had lost its Coulomb part to a backlash)
    picked_keys = {_key(f) for f in out}
    for fit, simpler in deferred:
        if _key(simpler) in picked_keys and allowed(fit):
            out.append(fit)
            seen.add(_key(fit))
    return out


def backfit(graph, rounds, *, fit, floor: dict, judge_model, choose, with_values, say, sensors=None,
            n: int = ALTERNATIVES):
    """Every chosen effect chosen again with the others in place (module docstring).

    Parameters
    ----------
    graph : BondGraph
        The nominal model.
    rounds : list of Round
        The rounds so far; a round whose effect is replaced gets ``chosen`` (the new fit),
        ``replaced`` (the old one) and ``backfit`` (the refits); every round that was backfitted
        gets ``backfit``.
    fit : callable
        ``fit(base, candidate, uncertain, bounds, abandon_above) -> CandidateFit``: a candidate
        fitted on the model `base`, with the parameters `uncertain` of `base` (the other effects')
        within their own `bounds` (:func:`diagnosis.fit.fit_candidate`): fitted beside the effect
        taken out, they may need to move far (a leak at one tank fitted beside a leak answered at
        the other).  `abandon_above` (None: fit fully) is :data:`~diagnosis.fit_in_turn.HOPELESS`
        times the best training cost of the round's refits so far: a refit stalled far above it
        is given up (on the exoskeleton, each refit took 10-40 s and the sensors' were hopeless
        beside a backlash).
    floor : dict str -> float
        The held-out noise floor per output (:func:`diagnosis.fit.noise_floor`).
    judge_model : callable
        ``judge_model(base) -> dict``: the held-out NRMSE per output of the model `base`.
    choose : callable
        ``choose(reference, fits) -> CandidateFit or None``: the round's rule.
    with_values : callable
        ``with_values(graph, values)``: `graph` with some parameters set.
    say : callable
        ``say(step, detail)`` progress.
    sensors : callable, optional
        ``sensors(outputs) -> list of Candidate``: the sensor candidates at the named outputs, fitted
        too (from their own guesses) where the round did not fit them: a sensor's error is judged on
        its own output only, the kind another effect's larger residual hides from graph location
        (:func:`diagnosis.place_choice.sensor_places`).  Only the outputs the other effects leave
        unexplained without this round's (:func:`diagnosis.fit.needs_explaining`) are asked for: a
        sensor at an output already at its floor changes no output the round's rule counts, and
        cannot explain the share it asks for (on the pam joint, two of its four outputs at most).

    Returns
    -------
    (list of CandidateFit, BondGraph)
        The effects after the sweep, in the rounds' order, and `graph` with all of them built in
        (the other effects' values as refitted with a replacing one).
    """
    chosen = [r for r in rounds if r.chosen is not None and r.chosen.candidate is not None]
    tuned = {}                  # the other effects' values refitted alongside a replacing effect

    def chosen_again(r) -> bool:
        """Round `r`'s effect chosen again with the other rounds' in place; whether it was replaced."""
        others = [c.chosen for c in chosen if c is not r]
        try:
            base = build_effects(graph, others, with_values)
            # the others' values as refitted beside a replacing effect; not this round's own (a mass
            # refitted beside a later round's effect is this round's to refit, not the reference's)
            theirs = {p.name for o in others for p in o.candidate.params}
            base = with_values(base, {k: v for k, v in tuned.items() if k in theirs and k in base.parameters()})
            names, bounds = refittable(base, others)
            reference = judge_model(base)
        except BondcosimError as exc:     # a later effect placed on the earlier one's element, a run diverging
            say("backfitting", f"round {rounds.index(r) + 1} left as chosen: without it, {exc}")
            return False
        # a candidate named for the nominal model may clash with the others' names (not with the
        # nominal's: a storage kind refits its element's own linear value), nor rewrite an element
        # another effect rewrites: a backlash in front of a spring that a later round gave a cubic
        # term, fitted on that model, was built before the cubic term in the final one, whose
        # held-out error was five times the nominal's (the detuned benchmark's msd, seed 6363 on the
        # fast plants, case 022)
        claimed = claims(o.candidate for o in others)
        tried = [(f.candidate, f.values) for f in alternatives(r.chosen, r.fits, r.reference, floor, n, *claimed)
                 if placed_in(base, f.candidate)]
        keys = {_key(c) for c, _ in tried}
        unexplained = needs_explaining(reference, floor)
        tried += [(c, None) for c in (sensors(unexplained) if sensors is not None else [])
                  if _key(c) not in keys and not clashes(c, claimed)]
        refits, best = [], np.inf
        for k, (cand, ended) in enumerate(tried, 1):
            if ended is not None and hasattr(cand, "with_starts"):     # a group of twins: its own guesses
                cand = cand.with_starts([cand.within_bounds({**ended, **tuned})])
            say("backfitting", f"round {rounds.index(r) + 1}: {cand} ({k}/{len(tried)})")
            # the round's own choice comes first and is fitted fully; a hopeless one after it is
            # given up as in the rounds (diagnosis.fit_in_turn)
            refit = fit(base, cand, names, bounds, HOPELESS * best if np.isfinite(best) else None)
            refit.n_params -= len(names)   # the others' parameters: the reference has them too
            refits.append(refit)
            best = min(best, train_cost(refit))
        r.backfit = refits
        winner = choose(reference, refits)
        # only a refit of the round's own choice, beaten, is replaced: not by a reading within the
        # tie margin of it with no fewer parameters (only tie-breakers would name it; see above)
        own_refit = next((f for f in refits if _key(f) == _key(r.chosen) and f.success), None)
        if (own_refit is not None and winner is not None and _key(winner) != _key(r.chosen)
                and not (own_refit.n_params <= winner.n_params
                         and within_tie(own_refit, winner, reference, floor))):
            say("backfitting", f"round {rounds.index(r) + 1}: {winner.candidate} replaces {r.chosen.candidate}")
            tuned.update({k: v for k, v in winner.values.items() if k in names})
            own = {p.name for p in winner.candidate.params}
            r.replaced, r.chosen = r.replaced or r.chosen, replace(winner, values={
                k: v for k, v in winner.values.items() if k in own or k not in names})
            return True
        return False

    # a second sweep over the rounds before the last one the first sweep replaced: they were
    # chosen beside the effect it replaced (SWEEPS)
    todo = list(chosen)
    for _ in range(SWEEPS):
        last = 0
        for k, r in enumerate(todo):
            if chosen_again(r):
                last = k
        todo = todo[:last]
        if not todo:
            break
    effects = [r.chosen for r in chosen]
    final = build_effects(graph, effects, with_values)
    return effects, with_values(final, {k: v for k, v in tuned.items() if k in final.parameters()})


def refittable(graph, effects) -> tuple[list, dict]:
    """``(names, bounds)``: the parameters of `effects` (built into `graph`) a refit fits again,
    a saturation limit released to its bound left out, and each one's own bounds (name ->
    (lower, upper))."""
    from .catalogue_common import released
    values = graph.parameters()
    names = [p.name for e in effects for p in e.candidate.params
             if p.name not in values or not released(values[p.name].value)]
    return names, {p.name: (p.lower, p.upper) for e in effects for p in e.candidate.params}


def _key(fit_or_candidate) -> tuple:
    cand = getattr(fit_or_candidate, "candidate", fit_or_candidate)
    return cand.kind, tuple(str(p) for p in getattr(cand, "places", (cand.place,)))


def placed_in(graph, cand) -> bool:
    """Whether every junction `cand` (or each member of a group) attaches to is in `graph`: a
    candidate of a later round may sit at a junction an earlier round's effect made (the 0-junction
    of a relaxing branch), which a model without that effect lacks (seed 8181's compound case 011,
    whose Dahl friction round 1 had answered as a relaxation, ended with a KeyError)."""
    members = getattr(cand, "members", None) or (cand,)
    places = [getattr(m, "place", None) for m in members]
    return all(getattr(p, "kind", None) != "junction" or p.name in graph.elements for p in places)
