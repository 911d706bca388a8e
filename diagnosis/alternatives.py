"""The readings a recording cannot tell apart from a round's answer.

Some kinds are the same effect on a given recording: a Coulomb friction :math:`F_c\\,\\mathrm{sign}(v)`
and a constant load at the same 1-junction where the velocity never reverses, a sensor offset and a
constant load on a linear spring.  :func:`diagnosis.fit.choose` names one of them (its tie-breakers:
fewer parameters, the plainer place, the training error, the catalogue order); this module says which
fits of other kinds fitted the recording as well:

* successful, with a finite held-out error, and accepted on their own by rule 3 of
  :func:`~diagnosis.fit.choose` (they explain at least :data:`~diagnosis.fit.MIN_SHARE` of the
  nominal excess error and lower its NRMSE by :data:`~diagnosis.fit.MIN_GAIN`);
* within :func:`~diagnosis.fit.choose`'s tie margin of the winner (:func:`~diagnosis.fit.within_tie`:
  priced score, or priced NRMSE on the outputs that need explaining, within
  :data:`~diagnosis.fit.TIE`), or as close before the price (since session 31: the price decides
  which reading is named, not whether the recording tells them apart; a carriage's Dahl
  hysteresis beside its mass fitted the truth's values to 0.5 % and predicted the held-out part
  as the Coulomb friction that answered, with one priced parameter more, and was not listed,
  detuned benchmark, seed 7474, case 028), unless its model holds the winner's
  (:func:`~diagnosis.kinds.base.holds`) and its prediction stays within
  :data:`~diagnosis.fit.COLLAPSED` noise standard deviations of the winner's: the winner with
  extra terms fitted to nothing is no other reading;
* and the held-out samples do not resolve the lower error of either over the other's
  (:func:`~diagnosis.holdout_resolution.resolution`, :math:`z <`
  :data:`~diagnosis.holdout_resolution.Z_RESOLVED`; a :math:`z` that cannot be computed, such as
  for identical predictions, resolves nothing).

One per kind (its lowest held-out error that passes), at most :data:`MAX_ALTERNATIVES`, lowest held-out
error first, but a richer law whose kind nests a listed one's (or the winner's) at the same place, its
prediction within :data:`~diagnosis.fit.COLLAPSED` noise standard deviations of that one's, after the
others: the plainer law with extra terms fitted to nothing is listed first when the list is full (a
carriage's Coulomb friction on motion that never reversed, answered as a constant load, was crowded
out of the list by the Stribeck and Coulomb-plus-viscous laws fitted to its prediction: seed 3641,
case 025).  Each carries the largest difference of its held-out prediction from the winner's in noise
standard deviations: a recording that excites that difference beyond the noise would tell them apart.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .fit import (COLLAPSED, MIN_GAIN, MIN_SHARE, TIE, acceptance, needs_explaining, unpriced_error, usable_fits,
                  within_tie)
from .errors import BondcosimError
from .holdout_resolution import Z_RESOLVED, largest_difference, resolution
from .kinds.base import REGISTRY, Kind, holds

__all__ = ["Alternative", "indistinguishable", "unexcited", "MAX_ALTERNATIVES"]

#: most alternatives reported per round
MAX_ALTERNATIVES = 3


@dataclass
class Alternative:
    """A fit of another kind that the recording cannot tell apart from a round's winner.

    Attributes
    ----------
    kind : str
        Its kind (``"nominal"`` for a refit of the uncertain nominal parameters alone).
    place : str
        Where it acts, as ``attached_to`` reads (``"junction v_mass"``; twins joined by ``", "``;
        ``""`` for a nominal refit).
    holdout_nrmse : dict str -> float
        Its held-out NRMSE per output.
    z : float
        :func:`~diagnosis.holdout_resolution.resolution` of the lower held-out error (the winner's or
        this fit's) over the other's, on the outputs that need explaining; below
        :data:`~diagnosis.holdout_resolution.Z_RESOLVED`; NaN where it cannot be computed.
    difference : float
        Largest absolute difference of the two held-out predictions over the noise standard
        deviation (the floor's), on the outputs that need explaining; NaN without predictions.
    n_params : int
        Its number of priced parameters.
    unexcited : str
        Why the recording never excites what sets this kind apart from the winner's, for a kind not
        fitted for that reason (:func:`unexcited`; its numbers are then the winner's); else "".
    structural : str
        Which of the answer's values a one-parameter twin reads as, for a reading not fitted because
        it is the answer's model rescaled (:func:`diagnosis.equivalent_readings.swapped_readings`;
        its numbers are then NaN); else "".
    """

    kind: str
    place: str
    holdout_nrmse: dict
    z: float
    difference: float
    n_params: int
    unexcited: str = ""
    structural: str = ""

    def to_json(self) -> dict:
        """``{"kind", "place", "holdout_nrmse": {output: nrmse}, "z", "difference", "n_params"}``,
        and ``"unexcited"`` and ``"structural"`` where set; NaN as ``None``."""
        finite = lambda x: float(x) if np.isfinite(x) else None   # noqa: E731
        out = {"kind": self.kind, "place": self.place,
               "holdout_nrmse": {o: finite(v) for o, v in self.holdout_nrmse.items()},
               "z": finite(self.z), "difference": finite(self.difference), "n_params": int(self.n_params)}
        return (out | ({"unexcited": self.unexcited} if self.unexcited else {})
                | ({"structural": self.structural} if self.structural else {}))


def indistinguishable(winner, fits, nominal_holdout: dict, *, noise: dict | None = None,
                      measured: dict | None = None, limit: int = MAX_ALTERNATIVES) -> list[Alternative]:
    """The fits of other kinds than `winner`'s that the held-out part cannot tell apart from it
    (module docstring), lowest held-out error first, one per kind, at most `limit`.

    Parameters
    ----------
    winner : CandidateFit
        The round's choice (:func:`diagnosis.fit.choose`).
    fits : iterable of CandidateFit
        Every fit of the round, with their held-out predictions (``extra["holdout_y"]``).
    nominal_holdout : dict str -> float
        Held-out NRMSE per output of the model the round started from.
    noise : dict str -> float, optional
        Noise floor per output as an NRMSE (:func:`diagnosis.fit.noise_floor`); default 0.
    measured : dict str -> ndarray, optional
        The recorded held-out outputs; without them nothing is resolved (z NaN).
    limit : int
        Most alternatives returned.

    Returns
    -------
    list of Alternative
    """
    floor = dict(noise or {})
    significant = needs_explaining(nominal_holdout, floor)
    if winner is None or not significant:
        return []
    found, kept = {}, {}
    for fit in sorted(usable_fits(fits, list(nominal_holdout)), key=lambda f: unpriced_error(f, significant)):
        if fit.kind == winner.kind or fit.kind in found:
            continue
        if not (_accepted(nominal_holdout, fit, floor) and (within_tie(fit, winner, nominal_holdout, floor)
                                                            or _as_close_unpriced(fit, winner, significant))):
            continue
        if holds(fit.candidate, winner.candidate) and largest_difference(
                measured, _prediction(winner), _prediction(fit), significant, floor) < COLLAPSED:
            continue
        z = _resolution_either_way(measured, winner, fit, significant)
        if not z >= Z_RESOLVED:
            kept[fit.kind] = fit
            found[fit.kind] = Alternative(fit.kind, _place_of(fit), dict(fit.holdout_nrmse), z,
                                          largest_difference(measured, _prediction(winner), _prediction(fit),
                                                             significant, floor),
                                          fit.n_params)
    richer = {k for k, fit in kept.items() if any(_nests_collapsed(fit, other, measured, significant, floor)
                                                   for other in (winner, *kept.values()))}
    return sorted(found.values(), key=lambda a: a.kind in richer)[:limit]     # stable: error order kept


def unexcited(graph, winner, experiment, x0=None) -> list[Alternative]:
    """The richer kinds of `winner`'s at its junction that the recording never excites there
    (:meth:`Kind.unexcited <diagnosis.kinds.base.Kind.unexcited>`), and so were not fitted: on this
    record each is the winner's law, and a recording that excites it would tell them apart.  A heat
    link's direction-dependent conductance where the heat flowed one way for all but a few per cent
    of the record was answered as a plain conductance, with no word that the other direction was
    never seen (seed 3737, case 022).  Each listed with the winner's numbers (z NaN, difference 0)
    and the reason, after the fitted alternatives and beside their limit; none for a winner the
    training part judged (which the held-out part cannot judge at all).

    Parameters
    ----------
    graph : BondGraph
        The model the winner was fitted on.
    winner : CandidateFit or None
    experiment : Experiment
        The part whose nominal run gives the junction's values (the fits' part).
    x0 : dict, optional
        That run's start state.
    """
    cand = getattr(winner, "candidate", None)
    if cand is None or winner.extra.get("judge") == "training":
        return []
    # a value pair's effect (a friction beside its mass refitted) is judged as the effect alone
    members = [m for m in getattr(cand, "members", (cand,)) if m.place.kind == "junction"]
    richer = [(m, [k for k in REGISTRY.values() if m.kind in k.nests and type(k).unexcited is not Kind.unexcited])
              for m in members]
    if not any(kinds for _, kinds in richer):
        return []
    from .catalogue_scales import junction_scales
    model = graph
    if hasattr(cand, "members"):     # the junction's values along the answer's own model
        try:
            model = cand.build(graph, winner.values)
        except BondcosimError:
            pass
    found = []
    for m, kinds in richer:
        if not kinds:
            continue
        _, values = junction_scales(model, m.place.name, experiment, x0=x0)
        for k in kinds:
            reason = k.unexcited(m.place.name, values) if values else ""
            if reason:
                found.append(Alternative(k.name, _place_of(winner), dict(winner.holdout_nrmse), float("nan"), 0.0,
                                         max(winner.n_params, k.feature_params), reason))
    return found


def _nests_collapsed(fit, other, measured, significant, floor) -> bool:
    """Whether `fit`'s kind nests `other`'s (:attr:`~diagnosis.kinds.base.Kind.nests`) at the same
    place and its held-out prediction stays within :data:`~diagnosis.fit.COLLAPSED` noise standard
    deviations of `other`'s: the plainer law with extra terms fitted to nothing."""
    if fit is other or fit.candidate is None or other.candidate is None or _place_of(fit) != _place_of(other):
        return False
    nested = other.kind in getattr(REGISTRY.get(fit.kind), "nests", {})
    return nested and largest_difference(measured, _prediction(other), _prediction(fit), significant, floor) < COLLAPSED


def _as_close_unpriced(fit, winner, significant) -> bool:
    """Whether `fit`'s held-out error on the outputs that need explaining, before the price, is
    within :data:`~diagnosis.fit.TIE` of `winner`'s (or lower)."""
    return unpriced_error(fit, significant) <= unpriced_error(winner, significant) * (1 + TIE) ** 2


def _accepted(nominal_holdout, fit, floor) -> bool:
    """Whether `fit` passes rule 3 of :func:`~diagnosis.fit.choose` on its own."""
    share, gain = acceptance(nominal_holdout, fit, floor)
    return share >= MIN_SHARE and gain >= MIN_GAIN


def _prediction(fit):
    return fit.extra.get("holdout_y")


def _resolution_either_way(measured, a, b, significant) -> float:
    """z of the lower held-out error of `a` and `b` over the other's (NaN when untestable)."""
    lower, higher = (a, b) if unpriced_error(a, significant) <= unpriced_error(b, significant) else (b, a)
    return float(resolution(measured, _prediction(lower), _prediction(higher), significant))


def _place_of(fit) -> str:
    """Where `fit`'s candidate acts, as the report's ``attached_to`` reads."""
    if fit.candidate is None:
        return ""
    places = getattr(fit.candidate, "places", None) or (fit.candidate.place,)
    return ", ".join(dict.fromkeys(str(p) for p in places))     # a value pair's members share a place
