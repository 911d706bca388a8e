"""The state of the diagnosis rounds, typed: one :class:`Round` per round and the
:class:`JointRefit` of all effects' parameters.

:func:`diagnosis.diagnose.diagnose` keeps a list of rounds (``report.rounds``): the first round's
fits and choice on the nominal model, then one per further effect looked for on the improved
graph.  Fields are read as attributes (``round.chosen``); reading them by key
(``round["chosen"]``, ``round.get("note")``, ``"joint" in round``) still works for code written
when the rounds were dicts, a key being present when its field is set.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from .errors import UnknownFieldError

__all__ = ["Round", "JointRefit"]


class _ReadByKey:
    """Read-only mapping access to a dataclass's fields that are set (not None)."""

    def __getitem__(self, key: str):
        if key not in self:
            raise UnknownFieldError(f"{type(self).__name__} has no field {key!r} set; set are "
                                    f"{', '.join(self.keys()) or '(none)'}")
        return getattr(self, key)

    def __contains__(self, key) -> bool:
        return key in self._fields() and getattr(self, key) is not None

    def get(self, key: str, default=None):
        return getattr(self, key) if key in self else default

    def keys(self):
        return [k for k in self._fields() if k in self]

    @classmethod
    def _fields(cls) -> tuple:
        return tuple(f.name for f in dataclasses.fields(cls))


@dataclass
class JointRefit(_ReadByKey):
    """All accepted effects' parameters refitted together (:func:`diagnosis.diagnose._joint_refit`).

    Attributes
    ----------
    fit : CandidateFit
        The joint fit.
    reference, improved : dict
        Held-out NRMSE per output before and after (``improved`` is ``reference`` when the fit failed).
    kept : bool
        Whether the held-out excess error beyond the noise floor did not grow (the joint values kept).
    graph : BondGraph or None
        The refitted model; ``y``: its simulated outputs; ``judged``: its
        :class:`~diagnosis.segments.Judged` held-out evaluation.
    """

    fit: object
    reference: dict
    improved: dict
    kept: bool = False
    graph: object = None
    y: object = None
    judged: object = None


@dataclass
class Round(_ReadByKey):
    """One diagnosis round.

    Attributes
    ----------
    chosen : CandidateFit or None
        The effect kept, or None ("nothing more").
    fits : list of CandidateFit
        Every fit of the round.
    reference, improved : dict
        Held-out NRMSE per output of the model the round started from, and with ``chosen``.
    seconds : float
        Time the round took.
    scores : list of PlaceScore, optional
        Graph location of further rounds (what is left of the residual).
    note : str, optional
        Why a further round stopped early (a numerical failure of its graph location).
    located : bool
        Whether a further round's graph location ran (False where it failed numerically: the
        round did not look, so "nothing more" is not a finding).
    graph, y, judged : optional
        The improved graph of a further round that kept an effect, its simulated outputs and its
        held-out evaluation (:class:`~diagnosis.segments.Judged`).
    joint : JointRefit, optional
        The joint refit, on the last round when there were two effects or more.
    diverged, window, floor, start : optional
        First round only: why the nominal simulation diverged ("" if it did not), the training
        window the fits used (first and last time, s), the noise floor per output, and the state
        the fits started from, in words.
    restarted : list of PlaceScore, optional
        First round only, under the segment judge: graph location on windows of the training part
        as long as the judge's segments, each restarted from a state fitted to the data.
    features : list of FeatureEvidence, optional
        The feature regression at each located junction (:mod:`diagnosis.features`).
    pruned : list of str, optional
        Candidates not fitted by simulation, their kind's features explaining far less than the best's.
    indistinguishable : list of Alternative, optional
        The fits of other kinds the held-out part cannot tell apart from ``chosen``
        (:func:`diagnosis.alternatives.indistinguishable`), lowest held-out error first; empty when
        nothing was chosen or the training part chose.
    replaced : CandidateFit, optional
        The round's first choice, where backfitting (:mod:`diagnosis.backfit`) replaced it by
        ``chosen``, chosen again with the other effects in place.
    backfit : list of CandidateFit, optional
        The round's best candidates fitted again with the other effects in place (backfitting).
    """

    chosen: object
    fits: list
    reference: dict
    improved: dict
    seconds: float = 0.0
    scores: list | None = None
    note: str | None = None
    located: bool = True
    graph: object = None
    y: object = None
    judged: object = None
    joint: JointRefit | None = None
    diverged: str | None = None
    window: list | None = None
    floor: dict | None = None
    start: str | None = None
    restarted: list | None = None
    features: list | None = None
    pruned: list | None = None
    indistinguishable: list | None = None
    replaced: object = None
    backfit: list | None = None
