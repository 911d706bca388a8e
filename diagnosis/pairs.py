"""Two effects at once, where no single one explains the recording.

The rounds of :func:`diagnosis.diagnose.diagnose` add one effect at a time: each round's best
single candidate must explain a share of the residual on its own (:data:`diagnosis.fit.MIN_SHARE`).
Two effects whose errors interact defeat that: a carriage whose force arrives through a lag *and*
whose spring hardens shows a velocity error that neither the lag nor the hardening lowers by a
tenth alone (each fitted without the other bends to the other's error), while the two together
take it below the noise (seed 5656, compound case 007: held-out NRMSE 0.103 -> 0.006, floor
0.008; the best single candidate 0.094).  Greedy rounds then answer "none" on a residual twelve
times the noise.

So when round 1 answers none although the residual is clearly beyond the noise (some output's
held-out NRMSE at least :data:`TRIGGER` times its floor), the best :data:`SINGLES` single-place
fits of the round, by training error (not the held-out error, which the choice is made on; a
candidate fitted without its partner may predict the held-out part worse than the nominal and
still fit the training part well), are fitted again in pairs (:class:`CandidatePair`), each
member started where its own fit ended.  The pairs join the round's fits and the round's own rule
chooses again: a pair pays for the parameters of both members, and must explain the share every
answer must.  A wrong single answer stalls the rounds as "none" does: a carriage's 1.66 s force
lag and 2.75 N constant load were answered as a saturation of the force input, which left the
velocity's held-out error at five times its floor, and round 2 found nothing on that model (seed
8181, compound case 000).  So where round 2 finds nothing on round 1's single answer while some
output stays at :data:`TRIGGER` times its floor, round 1's fits are paired too and its rule
chooses again; a pair that wins replaces the single answer (the pair of the two concealed effects
takes that velocity below its floor).  Not after round 1's choice itself: where round 2 and the
backfit complete a first answer (:mod:`diagnosis.backfit`), a pair chosen at once stopped the
rounds on the wrong two kinds (seed 3434, compound case 002).  Pairs of one place where one kind
extends the other (Coulomb and Coulomb + viscous friction) are not formed: the richer law is
already a candidate there.

**Selected pairs** (:func:`selected_pairs`) are fitted first wherever pairs are: where the feature
regression at a place found two kinds that together explain clearly more than any one (its
look-ahead, :func:`diagnosis.features.regress_kinds`), one kind that stands in for both answers
round 1 and leaves the second next to nothing, and the two need not be among the best singles by
training cost (an asymmetric damping for a viscous friction and a constant torque offset, which
alone explained 3 % of the estimate; compound seed 3738, case 025).  Such a look-ahead also makes
round 2's finding nothing a stall where the residual is under :data:`TRIGGER` times its floor: a
stand-in that leaves 1.7 times the floor there is still wrong (a drivetrain's Coulomb + viscous
friction and constant load, as on the issue's ball-screw axis).  Not in round 1 at once: on
the pneumatic cylinder's real recording the pressure-dependent friction and a constant load so
fitted took the answer from the friction and the load cell's gain error that the rounds find,
with a pressure slope of the friction 25 % off the by-hand fit's (the gain's offset, which grows
with the pressure, taken up by the friction).

**Rival pairs** (:func:`rival_pairs`, :func:`rival`): a stand-in need not stall the rounds.  Where
round 2 finds a second stand-in on the first one's model (an asymmetric damping, then a Stribeck
friction, for a geared pair's Coulomb + viscous friction and constant load), the features' pair was
never fitted; so after the rounds it is, and it replaces their answer where it predicts the
held-out part clearly better than their joint refit.

This is forward selection with a two-step look-ahead where the one-step search stalls (the
"nesting" problem of sequential selection; Pudil, Novovicova and Kittler, *Pattern Recognition
Letters* 15, 1994, on floating search).

**Value pairs** (:func:`value_pairs`) are fitted in round 1 (``max_effects`` >= 2): a nominal written from a rig's
documentation has its values a few per cent off, and an effect fitted alone then takes in part of
a value's error.  A geared pair's Coulomb + viscous friction beside its output inertia 3 % heavy
was answered as a Dahl friction, whose elastic phase after each reversal stood in for the inertia
(held-out error 1.5 times the floor), and the inertia refitted in round 2 could no longer pay
(detuned benchmark, seed 7474, case 032); with the inertia refitted beside the friction the right
law reaches the floor.  The round's best effects are each fitted with a value beside them; such a
pair is one effect (:func:`effect_count`), and competes only where it finishes the diagnosis
(:func:`finishing`).
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from itertools import combinations

import numpy as np

from .fit_in_turn import train_cost
from .kinds.base import extends
from .twins import CandidateGroup

__all__ = ["CandidatePair", "TRIGGER", "SINGLES", "VALUED", "FINISHED", "ANYWHERE", "wanted", "pair_candidates",
           "Stall", "stall", "selected_pairs", "value_pairs", "finishing", "effect_count", "VALUE_TIE", "targets",
           "claims", "clashes", "rival_pairs", "rival"]

#: pairs are fitted when some output's held-out NRMSE is at least this many times its floor
TRIGGER = 2.0
#: the single-place fits (lowest training error first) whose pairs are fitted: at most 15 pairs
SINGLES = 6
#: the effect fits (lowest training error first) refitted with their place's storage value
VALUED = 3
#: a value pair competes only where it takes every output within this many times its floor
FINISHED = 1.5
#: the values (lowest training cost alone first) a sensor's or an input's effect is paired with
ANYWHERE = 2
#: a junction effect is also paired with its place's next value whose cost alone is within this
#: share of the lowest (both given up at their start say little about which one is off)
VALUE_TIE = 0.05


@dataclass(frozen=True)
class CandidatePair(CandidateGroup):
    """Two candidates of different kinds or places fitted together, each with its own parameters
    (a :class:`~diagnosis.twins.CandidateGroup` whose members need not be twins).  The report
    lists one effect per member."""

    def __str__(self) -> str:
        return " and ".join(str(m) for m in self.members)


def effect_count(candidate) -> int:
    """The effects a round's chosen `candidate` adds: two for a pair, else one (a group of twins
    is one effect at several places).  A storage value refitted beside an effect
    (:func:`value_pairs`) adds no physics: such a pair is one effect."""
    if not isinstance(candidate, CandidatePair):
        return 1
    return max(1, sum(m.kind != "nominal_value" for m in candidate.members))


def targets(candidate) -> set:
    """The elements whose law `candidate` (a single, a pair or a group of twins) rewrites: its
    members' :attr:`~diagnosis.catalogue.Candidate.target` (a storage's cubic term, dead band or end
    stop; not a value refitted alone, :attr:`Kind.rewrites_target
    <diagnosis.kinds.base.Kind.rewrites_target>`).  Two such effects on one element are not
    combined: each rewrites the element's law from the one it finds, so the order of their builds
    would decide the model.  (Two that refit one parameter share its name, checked apart.)"""
    return {c.target for c in getattr(candidate, "members", (candidate,))
            if getattr(c, "target", None) and c.definition.rewrites_target}


def claims(candidates) -> tuple[set, set]:
    """``(parameter names, rewritten elements)`` of `candidates` together: what another effect
    joining them must not fit again or rewrite again (:func:`clashes`)."""
    candidates = list(candidates)
    return ({p.name for c in candidates for p in c.params}, set().union(*(targets(c) for c in candidates)))


def clashes(candidate, claimed: tuple) -> bool:
    """Whether `candidate` fits a parameter named in `claimed` (:func:`claims`) or rewrites the law
    of an element claimed there: one model with both would refit one value twice, or depend on the
    order of the two builds.  The one rule of the rounds, the pairs and the backfit."""
    names, rewritten = claimed
    return bool(names & {p.name for p in candidate.params} or rewritten & targets(candidate))


def wanted(nominal: dict, floor: dict) -> bool:
    """Whether the nominal model's held-out NRMSE (`nominal`, per output) is at least
    :data:`TRIGGER` times the noise floor (`floor`) on some output: a residual no single
    candidate explained that is clearly more than the noise."""
    return any(v >= TRIGGER * floor.get(o, 0.0) and v > 0 for o, v in nominal.items())


@dataclass(frozen=True)
class Stall:
    """Why round 2's finding nothing on round 1's single answer stalls the rounds (:func:`stall`).

    Attributes
    ----------
    far : bool
        Some output's held-out NRMSE stays at :data:`TRIGGER` times its floor or more: every pair
        of the best singles is fitted, not only the features' (:func:`selected_pairs`).
    why : str
        The reason, in words, for the report.
    """

    far: bool
    why: str


def stall(improved: dict, floor: dict, evidence) -> Stall | None:
    """Whether round 2's finding nothing on round 1's single answer (held-out NRMSE `improved` per
    output; `floor` the noise floors) means that answer was wrong: some output stays at
    :data:`TRIGGER` times its floor (:func:`wanted`), or round 1's feature regression at some place
    (`evidence`, its :class:`~diagnosis.features.FeatureEvidence`) named two kinds together by
    looking ahead, which a single answer cannot be (a drivetrain's Coulomb + viscous friction and
    constant load answered by an asymmetric damping at 1.7 times the floor).  None: not stalled.

    Examples
    --------
    >>> from types import SimpleNamespace as NS
    >>> stall({"v": 0.3}, {"v": 0.1}, []).why
    'the residual stayed far above the noise'
    >>> stall({"v": 0.17}, {"v": 0.1}, []) is None
    True
    >>> ev = NS(looked_ahead=True, selected=["viscous_friction", "constant_load"], place="junction w2")
    >>> stall({"v": 0.17}, {"v": 0.1}, [ev]).why
    "round 1's features had named two kinds together: viscous_friction + constant_load at junction w2"
    """
    if wanted(improved, floor):
        return Stall(True, "the residual stayed far above the noise")
    named = [f"{' + '.join(ev.selected)} at {ev.place}" for ev in evidence if ev.looked_ahead]
    return Stall(False, "round 1's features had named two kinds together: " + "; ".join(named)) if named else None


def pair_candidates(fits, n: int = SINGLES, besides=()) -> list[CandidatePair]:
    """Pairs of the `n` successful single-place fits of `fits` with the lowest training cost
    (``extra["train_cost"]``; one per kind and place), each member started where its fit ended
    (values clipped into its bounds: a saturation's unused limit is settled beyond them);
    lowest summed training cost first.  No pair of one place where one kind extends the other,
    none whose members share a parameter name or rewrite one element's law (:func:`clashes`), and
    none of the pairs `besides` (fitted with them: :func:`selected_pairs`)."""
    singles, seen = [], set()
    for f in sorted((f for f in fits if f.candidate is not None and not hasattr(f.candidate, "members")
                     and np.isfinite(train_cost(f))), key=train_cost):
        if str(f.candidate) not in seen:
            seen.add(str(f.candidate))
            singles.append(f)
    singles = singles[:n]
    fitted = {frozenset(map(str, p.members)) for p in besides}
    pairs = []
    for a, b in combinations(singles, 2):
        if extends(a.candidate, b.candidate) or extends(b.candidate, a.candidate):
            continue
        if frozenset((str(a.candidate), str(b.candidate))) in fitted:
            continue            # fitted beside them
        if clashes(a.candidate, claims([b.candidate])):
            continue
        pairs.append((train_cost(a) + train_cost(b),
                      CandidatePair((_started(a), _started(b)))))
    return [p for _, p in sorted(pairs, key=lambda cp: cp[0])]


def selected_pairs(fits, evidence, looked_ahead: bool = True) -> list[CandidatePair]:
    """At each place whose feature regression selected a pair of kinds by looking two kinds ahead
    (``FeatureEvidence.looked_ahead``, :func:`diagnosis.features.regress_kinds`; `evidence` the
    places' :class:`~diagnosis.features.FeatureEvidence`; with `looked_ahead` False, any two kinds
    it selected), the pair of that place's fits of the two
    kinds: per kind the fit with the lowest training cost, started where it ended (a fit given up
    keeps its own starts).  A kind that stands in for the two fits better alone than either does
    and answers round 1; on its model the second kind is left with next to nothing, and the rounds
    never meet the two together (compound benchmark, seed 3738, case 025: an asymmetric damping for
    a viscous friction and a constant torque offset).  They are fitted where :func:`pair_candidates`'
    are, before them."""
    singles = [f for f in fits if f.candidate is not None and not hasattr(f.candidate, "members")]
    out = []
    for ev in evidence:
        if (looked_ahead and not ev.looked_ahead) or len(ev.selected) != 2:
            continue
        members = []
        together = dict(zip(ev.selected, getattr(ev, "together", None) or ()))
        for label in ev.selected:
            own = [f for f in singles if getattr(ev.for_candidate(f.candidate), "label", None) == label]
            if own:
                f = min(own, key=lambda f: (train_cost(f), f.extra.get("train_cost", np.inf)))
                member = _started(f) if np.isfinite(train_cost(f)) else f.candidate
                members.append(_beside(member, together.get(label)))
        if len(members) == 2 and not clashes(members[0], claims([members[1]])):
            out.append(CandidatePair(tuple(members)))
    return out


def rival_pairs(fits, evidence, answered) -> list[CandidatePair]:
    """The pairs of kinds round 1's feature regression selected together at a place
    (:func:`selected_pairs`, by looking ahead or one kind after the other; `evidence` round 1's
    :class:`~diagnosis.features.FeatureEvidence`) that the rounds' answer does not name (`answered`,
    the candidates of its effects: not both kinds among theirs) and that are not among `fits`
    already; one per pair of kinds, at the first place that selected it.

    The rounds add one effect at a time, and each round's best single candidate may stand in for
    two: where round 2 then finds something on that model the rounds never stall
    (:func:`stall`), and the features' pair is never fitted.  On a geared pair's Coulomb + viscous
    friction and constant load, round 1's features selected the two, the rounds answered an
    asymmetric damping and a Stribeck friction at 1.6 times the floor (issue's ball-screw shape,
    ``python -m diagnosis.benchmark.ball_screw``, seed 11, case 007).  Such a pair is fitted
    after the rounds and replaces their answer where it predicts the held-out part clearly better
    (:func:`rival`)."""
    kinds = {m.kind for a in answered for m in getattr(a, "members", (a,))}
    fitted = {frozenset(map(str, f.candidate.members)) for f in fits if isinstance(f.candidate, CandidateGroup)}
    out, seen = [], set()
    for pair in selected_pairs(fits, evidence, looked_ahead=False):
        named = frozenset(m.kind for m in pair.members)
        if named <= kinds or named in seen or frozenset(map(str, pair.members)) in fitted:
            continue
        seen.add(named)
        out.append(pair)
    return out


def rival(fits, answer: dict, answer_params: int, nominal: dict, floor: dict):
    """``(fit, why)``: the fit of `fits` (the :func:`rival_pairs`' fits) whose priced held-out score
    (:func:`diagnosis.fit.priced_score`, rule 2 of :func:`diagnosis.fit.choose`, against the
    `nominal` held-out NRMSE) is lowest and below the rounds' answer's (held-out NRMSE `answer`,
    `answer_params` fitted parameters, its joint refit's where kept) beyond :data:`diagnosis.fit.TIE`,
    and whose held-out NRMSEs themselves, priced alike, are below the answer's beyond the tie
    :func:`~diagnosis.fit.choose` allows them (near the floor the excess magnifies differences the
    held-out part does not resolve), or is tied with it and fits fewer parameters (the plainer
    answer, as among tied fits in :func:`~diagnosis.fit.choose`), and which of the two, in words;
    None where none is.  Both are
    models of the recording fitted on its training part, judged alike; a tie keeps the rounds'
    answer unless the pair is simpler.  On the pneumatic cylinder's real recording the features' pair
    (pressure-dependent friction and a constant load, held-out NRMSE 0.053) stays behind the
    rounds' friction and load-cell gain refitted jointly (0.039).

    >>> from types import SimpleNamespace as NS
    >>> pair = NS(success=True, holdout_nrmse={"v": 0.11}, n_params=4)
    >>> rival([pair], {"v": 0.2}, 4, {"v": 0.5}, {"v": 0.1})[1]
    'better'
    >>> rival([pair], {"v": 0.112}, 4, {"v": 0.5}, {"v": 0.1}) is None
    True
    >>> rival([pair], {"v": 0.109}, 5, {"v": 0.5}, {"v": 0.1})[1]      # tied, and simpler
    'as well with fewer parameters'
    """
    from .fit import PARAMETER_PRICE, TIE, needs_explaining, priced_score
    significant = needs_explaining(nominal, floor)

    def raw(held, k):         # the held-out errors themselves, priced: near the floor the excess magnifies
        return sum(held[o] ** 2 for o in significant) * (1 + PARAMETER_PRICE) ** k

    bar, raw_bar = priced_score(answer, answer_params, nominal, floor), raw(answer, answer_params)
    best = None
    for f in fits:
        held = f.holdout_nrmse or {}
        if not (f.success and held and all(np.isfinite(v) for v in held.values())):
            continue
        score, raw_score = priced_score(held, f.n_params, nominal, floor), raw(held, f.n_params)
        better = score * (1 + TIE) < bar and raw_score * (1 + TIE) ** 2 < raw_bar
        # tied (neither lower beyond the tie), the simpler model is the plainer answer, as in choose
        simpler = (f.n_params < answer_params and score <= bar * (1 + TIE)
                   and raw_score <= raw_bar * (1 + TIE) ** 2)
        if (better or simpler) and (best is None or score < best[0]):
            best = (score, f, "better" if better else "as well with fewer parameters")
    return None if best is None else best[1:]


def _beside(cand, evidence):
    """`cand` with a first start at its kind's coefficients fitted beside the other selected kind's
    (`evidence`, a :attr:`FeatureEvidence.together <diagnosis.features.FeatureEvidence>` entry), where
    there are such, and the bounds widened to admit them (:func:`diagnosis.features.admitting`):
    each fitted alone took in part of the other (a DC motor's Coulomb + viscous friction beside a
    constant load of 0.46 N m, fitted from where each ended alone, stopped at twice the held-out
    error of the rounds' answer with no viscous term and the load at its bound, 0.29 N m;
    ball-screw seed 12, case 008)."""
    if evidence is None:
        return cand
    from .features import with_feature_start
    return with_feature_start(cand, evidence, first=True)


def _started(fit):
    """`fit`'s candidate with its first start where it ended, within its bounds (first: a group
    tries its members' i-th starts side by side)."""
    cand = fit.candidate
    ended = cand.within_bounds({**cand.guesses(), **fit.values})
    return replace(cand, starts=(ended,) + tuple(cand.starts))


def value_pairs(fits, n: int = VALUED, evidence=None) -> list[CandidatePair]:
    """The `n` successful single-place effect fits of `fits` with the lowest training cost, and the
    simpler kinds each extends at its place (:func:`~diagnosis.kinds.base.extends`), each paired
    with a ``nominal_value`` fit whose value it does not refit itself (:func:`clashes`), each
    member started where its fit ended: the effect with its junction's mass, inertia, inductance,
    spring or damper refitted beside it.

    The value is the one whose fit alone reached the lowest training cost at the effect's own
    place, for an effect at a junction (none there: no pair), and the next one too where its cost
    is within :data:`VALUE_TIE` of that (a mass 2.8 % heavy and a spring, both given up at their
    nominal values after four evaluations, costs 0.0198 and 0.0197: the spring alone was paired
    with the viscous friction concealed beside the mass, and a relaxation answered; detuned seed
    3739, case 005); for a sensor's or an input's, each of
    the :data:`ANYWHERE` values with the lowest anywhere: an RLC's voltage sensor offset beside an
    inductance 4 % off was answered as a constant load at the loop when only the junction effects
    were paired (detuned benchmark, seed 6363, case 024), and a pressure sensor's offset as a Dahl
    friction beside a pipe's inertance 2.8 % off when the one value that fitted best alone, an
    outlet's resistance, was its only partner (seed 8585, case 037).  A value fit given up as
    hopeless beside the effect's error (:mod:`~diagnosis.fit_in_turn`) counts with its training
    cost when given up: a motor's inertia 4.6 % off beside a Coulomb friction (seed 6363, case
    013).  The simpler kinds join because a richer kind's pair may end with its extra terms idle,
    and the choice then drops it (:func:`diagnosis.fit.choose`): there the Coulomb + viscous
    friction beside the inertia ended with no viscous term, and Coulomb friction itself was the
    fourth-best effect.

    An effect that fits badly alone may be the one the value needs beside it: a carriage's mass
    4.5 % light beside a viscous friction, which alone cannot stand in for the mass, fitted worst
    of the frictions alone, and a Dahl friction beside the mass (its elastic phase again standing
    in for the mass) answered (detuned benchmark, seed 8585, case 007).  So with `evidence`
    (``fit -> KindEvidence or None``, :func:`diagnosis.features.evidence_lookup`), at each place
    the effect whose kind's features leave least of the located estimate with the place's values
    fitted beside them (:attr:`KindEvidence.with_values <diagnosis.features.KindEvidence>`, priced
    per parameter as the regression is) is paired too, even where its fit alone was given up: a
    carriage's hardening spring, whose linear term alone stood in for the mass 3 % light, fitted so
    badly alone that it was given up (seed 7474, case 035)."""
    singles = [f for f in fits if f.candidate is not None and not hasattr(f.candidate, "members")]
    values = sorted((f for f in singles if f.candidate.kind == "nominal_value"
                     and np.isfinite(f.extra.get("train_cost", np.inf))), key=lambda f: f.extra["train_cost"])
    # the successful effect fits by training cost, then those given up (the evidence may ask for one)
    effects = sorted((f for f in singles if f.candidate.kind != "nominal_value"),
                     key=lambda f: (train_cost(f), f.extra.get("train_cost", np.inf)))

    def partners(f):
        fitting = [v for v in values if not clashes(f.candidate, claims([v.candidate]))]
        if f.candidate.place.kind in ("junction", "law"):
            here = [v for v in fitting if str(v.candidate.place) == str(f.candidate.place)]
            near = [v for v in here if v.extra["train_cost"] <= (1 + VALUE_TIE) * here[0].extra["train_cost"]]
            return near[:ANYWHERE]
        return fitting[:ANYWHERE]

    paired = {}                   # str(effect) -> (its fit, its partners), the first fit of each
    for f in effects:
        paired.setdefault(str(f.candidate), (f, partners(f)))
    effects = [f for f, with_values in paired.values() if with_values]
    asked = _best_with_values(effects, evidence)
    effects = [f for f in effects if np.isfinite(train_cost(f))]
    chosen = effects[:n]
    for f in effects[:n]:         # the simpler kinds each extends, after the best n
        taken = {str(c.candidate) for c in chosen}
        chosen += [g for g in effects if str(g.candidate) not in taken and extends(f.candidate, g.candidate)]
    taken = {str(c.candidate) for c in chosen}
    chosen += [f for f in asked if str(f.candidate) not in taken]
    return [CandidatePair((_started(f), _started(v))) for f in chosen for v in paired[str(f.candidate)][1]]


def _best_with_values(effects, evidence) -> list:
    """Per place, the fit of `effects` whose kind's evidence leaves least with the place's values
    beside it (:attr:`KindEvidence.with_values_score <diagnosis.features.KindEvidence>`)."""
    best = {}
    for f in effects:
        ev = evidence(f) if evidence is not None else None
        left = getattr(ev, "with_values_score", np.nan)
        place = str(f.candidate.place)
        if np.isfinite(left) and (place not in best or left < best[place][0]):
            best[place] = (left, f)
    return [f for _, f in best.values()]


def finishing(fits, floor: dict) -> list:
    """The value-pair `fits` (:func:`value_pairs`) that take every output's held-out NRMSE within
    :data:`FINISHED` times its `floor`: a value refitted beside an effect finishes a diagnosis,
    it does not stand in for missing physics.  A spring's value refitted beside a viscous friction
    took in part of a backlash in front of that spring, left the error at twice its floor (x 0.103,
    floor 0.052), won round 1 over the Coulomb + viscous law, and round 2 found no backlash beside
    the refitted spring (compound benchmark, seed 3434, case 002); the value pairs that answered
    the detuned benchmark's friction beside an inertia off ended within 1.05 times their floor."""
    return [f for f in fits if f.success and f.holdout_nrmse
            and all(v <= FINISHED * floor.get(o, 0.0) for o, v in f.holdout_nrmse.items())]
