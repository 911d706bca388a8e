"""Name the physics from the estimate: a feature regression per kind at a located junction.

Graph location (:mod:`diagnosis.graph_location`) estimates, at each junction, a free
extra effort (1-junction) or flow (0-junction) :math:`d(t)` from the linearised
response of the outputs to it.  Here :math:`d` is restricted instead to the physics
each kind of the catalogue would add there: a few *feature signals*
:math:`\\phi_{k,j}(t)` computed at the junction along the run *corrected* by the
location's estimate :math:`\\hat d` (from the same start as the location),

.. math::

    d(t) = \\sum_j \\beta_{k,j}\\, \\phi_{k,j}(t), \\qquad
    r \\approx S_{\\phi_k} \\beta_k,

where :math:`r = r_c + S_c \\hat d` is the nominal residual linearised about the corrected
run (:math:`r_c` the corrected run's residual; a Gauss-Newton step from the estimate),
weighted by :math:`1/\\sigma_o` (the measurement noise), and :math:`S_{\\phi_k}` the
linearised responses of the outputs to each feature signal injected at the junction
along the corrected run (:class:`~diagnosis.graph_location_linear.LinearisedResponse`,
the location's own machinery).  :math:`\\beta_k` is fitted by least squares on the first 70 % of the
rows and judged on the last 30 % (a time split): the *validated share* of kind k is
:math:`1 - \\mathrm{SSE}_{val}(k) / \\mathrm{SSE}_{val}(0)`.  Kinds are ranked by the
penalised validation error :math:`\\mathrm{SSE}_{val}(k) (1 + \\rho)^{m_k}`
(:data:`FEATURE_PRICE` per parameter, :math:`m_k` the kind's parameters in
:data:`KIND_FEATURES`); a forward selection over kind groups (at most
:data:`MAX_SELECTED`) says which kinds together explain the estimate.  Under the segment judge (a
drifting nominal) every segment's start state is fitted too and the kinds are validated across
the segments (:mod:`diagnosis.feature_restarts`).

The features per kind are each kind's own (:meth:`diagnosis.kinds.base.Kind.features`, from the
junction's :class:`~diagnosis.kinds.feature_signals.FeatureSignals`; :data:`KIND_FEATURES`
lists them), with
:math:`v` the junction's common flow (a velocity at a mechanical 1-junction),
:math:`s = \\tanh(v / v_\\varepsilon)` a nearly sharp sign (:math:`v_\\varepsilon`
:data:`SIGN_FRACTION` = 1 % of the RMS flow), :math:`q` the content of a C on the
junction and :math:`e` the common effort of a 0-junction:

* ``coulomb_friction`` :math:`s`; ``viscous_friction`` :math:`v`;
  ``coulomb_viscous_friction`` :math:`s, v`; ``asymmetric_viscous_friction`` :math:`\\max(v, 0), \\min(v, 0)`;
  ``quadratic_drag`` :math:`v |v|`;
* ``stribeck_friction`` :math:`s, e^{-(v/v_s)^2} s` for :math:`v_s` = 0.1, 0.3, 1 times
  the RMS flow;
* ``pressure_dependent_friction`` :math:`s, (P - \\bar P) s` per pressure variable;
* ``modulated_friction`` :math:`s, (L_\\tau m - \\bar m) s` per modulating signal
  :math:`m` and first-order lag :math:`\\tau` of 2, 20, 200 sample intervals;
* ``hysteresis`` the normalised Dahl state :math:`\\dot z = \\alpha (v - |v| z)` for
  :math:`\\alpha X` = 1, 3, 10, 30, 100 (X the RMS displacement), coefficient :math:`F_h`;
* ``constant_load`` 1;
* ``nonlinear_stiffness`` :math:`q^3, q` per C on a 1-junction (the cubic term and the
  refitted linear value); ``backlash`` :math:`\\mathrm{clip}(q, -b, b)` for b = 0.1, 0.3,
  1 times the RMS of q; ``saturation`` (end stops) the hinges
  :math:`\\max(q - q_{hi}, 0), \\min(q - q_{lo}, 0)` at the 75/25, 90/10 and 97/3 %
  quantiles of q;
* at a 0-junction ``leak`` :math:`e - P_{amb}`, ``constant_load`` 1 and ``saturation``
  (an overflow) :math:`\\max(q - q_{hi}, 0)`.

``heat_transfer`` and a C's stiffness at a 0-junction (an effort law, not an extra
flow) have no features: they keep today's path (fitted by simulation, no evidence).
The coefficients are reported with the catalogue's sign convention (an element
that *takes* effort or flow from the junction), so a Coulomb friction's
coefficient is its level :math:`F_c`.

Anchors: SINDy discrepancy models (Kaheman, Kaiser, Brunton et al. 2019, "Learning
discrepancy models from experimental data", arXiv:1909.08574; Ebers, Steele and
Kutz 2024, "Discrepancy modeling framework", SIAM J. Appl. Dyn. Syst. 23(1)) regress
the discrepancy on an unstructured library of terms; here each group of columns is
one kind of physics at one bond-graph place, so the winner is named and then
inserted and refitted as a real element by :mod:`diagnosis.fit`.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from itertools import combinations

import numpy as np

from .catalogue_common import junction_elements
from .kinds import REGISTRY
from .kinds.feature_signals import SIGN_FRACTION, FeatureSignals, dahl_state
from .kinds.modulated_friction import modulating_signals
from .kinds.nominal_value import value_columns
from .catalogue_scales import pressure_variables
from .errors import BondcosimError
from .feature_restarts import restarted
from .law_places import at_junction

__all__ = ["KIND_FEATURES", "SIGN_FRACTION", "FEATURE_PRICE", "MAX_SELECTED", "KindEvidence", "FeatureEvidence",
           "evidence_lookup", "prune_candidates", "with_feature_starts", "with_feature_start",
           "admitting", "ADMIT", "prefer_by_evidence",
           "feature_evidence", "regress_kinds", "left_with", "dahl_state"]

#: kind -> (junction kinds it applies at, the feature columns in words, the parameters it is
#: priced by), read off each kind's class (:attr:`~diagnosis.kinds.base.Kind.feature_doors`,
#: ``feature_names``, ``feature_price``; the columns are its
#: :meth:`~diagnosis.kinds.base.Kind.features`), in the catalogue order
KIND_FEATURES = {name: (kind.feature_doors, kind.feature_names, kind.feature_price)
                 for name, kind in REGISTRY.items() if kind.feature_doors}

#: relative price of each parameter on the validation error (parsimony)
FEATURE_PRICE = 0.05
#: kinds the forward selection adds at most
MAX_SELECTED = 3
#: share of the validation rows (the last ones)
VALIDATION = 0.3
#: least validated share, and least drop of the weighted validation SSE per column (in
#: noise variances), for a kind to count as significant
MIN_SHARE, MIN_DROP_PER_COLUMN = 0.02, 25.0
#: least share of the starting excess beyond the noise a pair of kinds must explain more than the
#: forward selection to replace it (:func:`_look_ahead`): above the linearisation's own error
#: (0.008-0.02 % of the start measured), below a friction's share beside a constant force (0.3 %)
LOOK_AHEAD = 0.001
_MAX_ROWS = 10000


@dataclass
class KindEvidence:
    """How much of the residual one kind's features explain at one place.

    Attributes
    ----------
    kind : str
        Catalogue kind.
    variant : str or None
        The candidate it matches: a pressure or modulating signal's expression
        (``Candidate.regime``), a C element's name (``Candidate.target``), else None.
    detail : str
        The variant's free choice in words (``v_s = 0.03 m/s``, ``lag 0.02 s``), or "".
    share : float
        Validated share of the weighted residual explained (last 30 % of the rows),
        at most 1 (negative: worse than nothing).
    score : float
        Penalised validation SSE relative to the no-correction SSE (lower is better).
    coefficients : dict str -> float
        Feature -> coefficient in the catalogue's sign convention (fitted on all rows),
        in the junction's effort (flow) unit per unit of the feature.
    significant : bool
        The share is at least :data:`MIN_SHARE` and the drop of the weighted validation
        SSE at least :data:`MIN_DROP_PER_COLUMN` noise variances per column.
    excess_share : float
        Validated share of the residual *beyond the measurement noise* explained (the
        weighted validation SSE less one noise variance per value), at most 1.
    drop : float
        Drop of the weighted validation SSE, in noise variances.
    grid : tuple of float
        The variant's free choice as numbers (``FeatureGroup.grid``: an end stop's limits), or ().
    with_values : float
        What this kind's features leave of the residual with the junction's own I and C values
        refitted beside them (:func:`~diagnosis.kinds.nominal_value.value_columns`), in noise
        variances per validation value (:func:`left_with`; 1 would be the noise alone, the
        linearisation leaves a few); NaN where the junction has none.  The kind that leaves least
        is the one to refit beside them (:func:`diagnosis.pairs.value_pairs`).
    """

    kind: str
    variant: str | None
    detail: str
    share: float
    score: float
    coefficients: dict
    significant: bool
    excess_share: float = 0.0
    drop: float = 0.0
    grid: tuple = ()
    with_values: float = float("nan")

    @property
    def label(self) -> str:
        """``kind`` or ``kind (variant)``."""
        return f"{self.kind} ({self.variant})" if self.variant else self.kind

    @property
    def with_values_score(self) -> float:
        """:attr:`with_values` priced per parameter as the regression's scores are
        (:data:`FEATURE_PRICE`); NaN where the junction has no values."""
        return self.with_values * (1.0 + FEATURE_PRICE) ** REGISTRY[self.kind].feature_price


@dataclass
class FeatureEvidence:
    """The feature regression at one junction place.

    Attributes
    ----------
    place : Place
    kinds : list of KindEvidence
        Best (lowest penalised score) first; one entry per kind and variant group.
    selected : list of str
        Labels the forward selection over kinds kept, in the order added, or the pair it missed
        (:attr:`looked_ahead`).
    selected_share : float
        Validated share of the selected kinds together.
    unit : str
        The junction's effort (1-junction) or flow (0-junction) unit.
    looked_ahead : bool
        Whether :attr:`selected` is a pair of kinds that together explain clearly more than the
        forward selection's kinds, found by looking two kinds ahead (:func:`regress_kinds`): one
        kind that stands in for the two misleads one effect at a time, so the pair is fitted
        together too (:func:`diagnosis.pairs.selected_pairs`).
    together : list of KindEvidence
        Where two kinds or more are selected, each one's evidence with its coefficients fitted
        beside the others' (aligned with :attr:`selected`): a pair fitted by simulation starts
        there too (:func:`diagnosis.pairs.selected_pairs`); each kind fitted alone has taken in
        part of the other (a Coulomb friction's level a constant load's).
    """

    place: object
    kinds: list
    selected: list = field(default_factory=list)
    selected_share: float = 0.0
    unit: str = ""
    looked_ahead: bool = False
    together: list = field(default_factory=list)

    def for_candidate(self, candidate) -> KindEvidence | None:
        """The evidence of `candidate`'s kind (and variant) here, or None when it has no features."""
        place = getattr(candidate, "place", None)
        if place is None or hasattr(candidate, "members") or (place.kind, place.name) != (self.place.kind,
                                                                                           self.place.name):
            return None          # a twin group (several places) has no single place's evidence
        key = getattr(candidate, "regime", None) if candidate.kind in ("pressure_dependent_friction",
                                                                      "modulated_friction") \
            else getattr(candidate, "target", None)
        for k in self.kinds:
            if k.kind == candidate.kind and (k.variant is None or k.variant == key):
                return k
        return None

    def best(self) -> KindEvidence | None:
        """The best significant kind, or None."""
        return next((k for k in self.kinds if k.significant), None)

    def best_with_values(self) -> KindEvidence | None:
        """The kind that leaves least with the junction's values beside it
        (:attr:`KindEvidence.with_values_score`), or None where the junction has no values."""
        scored = [k for k in self.kinds if np.isfinite(k.with_values_score)]
        return min(scored, key=lambda k: k.with_values_score) if scored else None

    def to_json(self) -> dict:
        """JSON form: place, unit, selected kinds and per kind its share, what it leaves with the
        junction's values beside it (None where there are none) and its coefficients."""
        return {"place": str(self.place), "unit": self.unit, "selected": list(self.selected),
                "selected_share": _finite(self.selected_share), "looked_ahead": bool(self.looked_ahead),
                "kinds": [{"kind": k.kind, "variant": k.variant or "", "detail": k.detail,
                           "share": _finite(k.share), "excess_share": _finite(k.excess_share),
                           "significant": bool(k.significant), "with_values": _finite(k.with_values),
                           "coefficients": {n: _finite(v) for n, v in k.coefficients.items()}}
                          for k in self.kinds]}

    def summary(self, n: int = 4) -> str:
        """One line: the best kinds' validated shares of the residual beyond the noise, and the selection."""
        shown = ", ".join(f"{k.label} {100 * max(k.excess_share, 0.0):.0f} %" for k in self.kinds[:n])
        chosen = " + ".join(self.selected) if self.selected else "none above the noise"
        ahead = " (together, looking two kinds ahead)" if self.looked_ahead else ""
        return f"{shown}; selected: {chosen}{ahead}"


def _finite(x):
    x = float(x)
    return x if np.isfinite(x) else None


def _signals(graph, junction: str, regime_variables) -> dict:
    """Expressions to read along the run at `junction`: label -> expression."""
    bonds = [b for b, _ in graph.bonds_of(junction)]
    out = {"flow": f"f_{bonds[0].name}", "effort": f"e_{bonds[0].name}"}
    if graph.elements[junction].kind == "1":
        out.update({f"pressure:{expr}": expr for expr in pressure_variables(graph).values()})
        out.update({f"signal:{expr}": expr for expr in modulating_signals(graph, junction, regime_variables).values()})
    for element, bond in junction_elements(graph, junction):
        if element.kind == "C" and element.state:
            out[f"content:{element.name}"] = element.state
            out[f"c_effort:{element.name}"] = f"e_{bond.name}"
        elif element.kind == "I" and element.state:
            out[f"momentum:{element.name}"] = element.state
    return out


def _with_travel(graph, junction: str):
    """`graph` with a probe that integrates the flow of 1-junction `junction` from 0 at the start,
    as a candidate's own state would (a periodic load's travel), and the probe's state name.  The
    travel summed from the sampled flow is not that: a velocity that jumps with each held sample
    of an input (a position follower whose time constant is near the sampling step) is sampled at
    its jumps, and its trapezoids overstate the travel (by 40 % at a step of 0.7 time constants:
    seed 4401's cylinder, case 002, whose periodic load the features then found at 1.4 times its
    period)."""
    from bondgraph import EquationElement

    from .catalogue_common import junction_units
    from .kinds.friction_common import displacement_unit
    state = f"travel_probe_{junction}"
    probe = EquationElement(f"travel_probe_at_{junction}", ports={"m": "in"}, outputs={"e_m": "0"},
                            states={state: "f_m"}, initial={state: 0.0},
                            units={state: displacement_unit(junction_units(graph, junction)[1])},
                            description=f"the travel of {junction}, read by the features")
    return graph.insert(probe, at=junction, bond=f"b_travel_probe_{junction}"), state


def _kind_variants(kind, signals: FeatureSignals) -> list:
    """``(variant, detail, names, columns (n, m))`` of `kind` at a junction from its `signals`
    (:func:`_signals`, read along the run): the kind's
    :meth:`~diagnosis.kinds.base.Kind.features`, where it applies."""
    definition = REGISTRY[kind]
    door = "1" if signals.one else "0"
    if door not in definition.feature_doors or not definition.admits(door, signals.domain):
        return []
    return list(definition.features(signals))


def regress_kinds(responses: dict, r, w, *, price: float = FEATURE_PRICE, validation: float = VALIDATION,
                  parameters=None, lost: int = 0, folds=None, signs=None):
    """Rank kind groups by validated least squares of the residual on their responses.

    Parameters
    ----------
    responses : dict key -> (names, S (rows, ny, m))
        Per kind group (a kind and variant), the linearised responses of the outputs to
        its feature columns at the kept rows.
    r : ndarray, shape (rows, ny)
        Residual at the kept rows (output units).
    w : ndarray, shape (ny,)
        Output weights, 1/sigma^2.
    price, validation : float
        Relative price per parameter; share of the rows (the last ones) held out.
    parameters : dict key -> int, optional
        Parameters each group is priced by (default: its number of columns).
    lost : int
        Degrees of freedom the validation rows have lost (a restarted regression's start states,
        :mod:`diagnosis.feature_restarts`): the noise left there is that many variances less.
    folds : ndarray of int, shape (rows,), optional
        Each row's validation fold: every fold f >= 0 is validated on the coefficients fitted on
        the other rows, and the validation SSE sums over the folds (rows of fold -1 are only
        fitted on).  Default: the time split, the last `validation` share of the rows one fold.
    signs : dict key -> tuple of int, optional
        The law's sign of each group's leading coefficients (``Kind.feature_signs``: +1 where the
        catalogue-sign coefficient cannot be negative, a friction level or a damping that takes
        energy).  A group whose coefficients on all rows break it is not significant, and no
        selection (forward or looked ahead) keeps a group whose coefficients fitted with the others'
        break it (:func:`_breaks_sign`).

    Returns
    -------
    (dict key -> (share, score, beta, significant, excess, drop), Selection)
        Per group: validated share, penalised score (relative to the no-correction SSE),
        coefficients fitted on all rows (in the responses' sign), significance, the share of
        the validation SSE *beyond the noise* explained (the noise: one variance per weighted
        value) and the drop of the weighted validation SSE (noise variances); the groups
        selected (the forward selection's, or the pair :func:`_look_ahead` finds better) and
        their joint validated share.
    """
    rows, ny = r.shape
    sw, b, folds = _weighted_split(r, w, validation, folds)
    b_val = b[folds >= 0].reshape(-1)
    sse0 = float(b_val @ b_val)
    if not sse0 > 0:
        return {}, Selection([], 0.0)

    def fit(S):
        return _validated_sse(S, sw, b, folds)

    noise = float(b_val.size - lost)
    excess0 = max(sse0 - noise, MIN_DROP_PER_COLUMN)
    out = {}
    for key, (_, S) in responses.items():
        if not np.isfinite(S).all() or S.shape[0] != rows:
            continue
        sse, rank = fit(S)
        A_all = (S * sw[None, :, None]).reshape(-1, S.shape[2])
        beta = np.linalg.lstsq(A_all, b.reshape(-1), rcond=1e-10)[0]
        share = 1.0 - sse / sse0
        k = (parameters or {}).get(key, S.shape[2])
        significant = (share >= MIN_SHARE and sse0 - sse >= MIN_DROP_PER_COLUMN * max(rank, 1)
                       and not _breaks_sign({key: beta}, signs))
        excess = min((sse0 - sse) / excess0, 1.0)
        out[key] = (share, sse / sse0 * (1.0 + price) ** k, beta, bool(significant), float(excess), sse0 - sse)
    # forward selection: a kind is added while it lowers the penalised score, drops the SSE by at
    # least MIN_DROP_PER_COLUMN noise variances per column and by 30 % of what is left above the
    # noise (N: the validation values, each of unit noise variance after weighting), and what is
    # left is still 5 % of the excess the residual started with
    selected, current, cols, sse_now = [], 1.0, [], sse0
    for _ in range(MAX_SELECTED):
        if selected and sse_now - noise <= 0.05 * (sse0 - noise):
            break
        trial = []
        for key in out:
            if key in selected or not out[key][3] or any(k[0] == key[0] for k in selected):
                continue
            S = np.concatenate(cols + [responses[key][1]], axis=2)
            if _breaks_sign(_joint_coefficients(responses, selected + [key], sw, b, alone=True), signs):
                continue
            sse, _ = fit(S)
            k = sum((parameters or {}).get(g, responses[g][1].shape[2]) for g in selected + [key])
            trial.append((sse / sse0 * (1.0 + price) ** k, sse, key))
        if not trial:
            break
        score, sse, key = min(trial, key=lambda x: x[0])
        drop = sse_now - sse
        if (score >= current or drop < MIN_DROP_PER_COLUMN * responses[key][1].shape[2]
                or drop < 0.3 * max(sse_now - noise, 0.0)):
            break
        selected.append(key)
        cols.append(responses[key][1])
        current, sse_now = score, sse

    def lawful(keys):
        return not _breaks_sign(_joint_coefficients(responses, list(keys), sw, b), signs)

    pair = _look_ahead(out, responses, fit, sse0, noise, price, parameters, current, sse_now, lawful)
    if pair is not None:
        selected, sse_now = list(pair[0]), pair[1]
    return out, Selection(selected, 1.0 - sse_now / sse0, pair is not None,
                          _joint_coefficients(responses, selected, sw, b))


def _joint_coefficients(responses, keys, sw, b, alone: bool = False) -> dict:
    """The coefficients of the groups `keys` fitted together on all rows (the responses' sign), per
    group: where two kinds are selected, each one's coefficients beside the other's, not alone
    (one group: none, unless `alone`)."""
    if len(keys) < (1 if alone else 2):
        return {}
    S = np.concatenate([responses[k][1] for k in keys], axis=2)
    beta = np.linalg.lstsq((S * sw[None, :, None]).reshape(-1, S.shape[2]), b.reshape(-1), rcond=1e-10)[0]
    cuts = np.cumsum([0] + [responses[k][1].shape[2] for k in keys])
    return {k: beta[cuts[i]:cuts[i + 1]] for i, k in enumerate(keys)}


def _breaks_sign(coefficients: dict, signs) -> bool:
    """Whether a group's coefficients (key -> responses'-sign array, as fitted) break its law's
    sign (`signs`, key -> ``Kind.feature_signs``): a catalogue-sign coefficient (the responses'
    negated) below 0 where the sign is +1.  A Coulomb friction's level fitted at -1.59 N stood in
    for a constant load pushing a carriage along its one-way motion (``sign(v)`` is 1 there) and
    was selected beside a hardening spring; the fit of that pair, its level bound at 0, was given up,
    and the answer was ``none`` (carriage compound benchmark, seed 4302, case 014)."""
    if not signs:
        return False
    for key, beta in coefficients.items():
        for sign, c in zip(signs.get(key, ()), np.ravel(beta)):
            if sign > 0 and -c < 0:
                return True
    return False


@dataclass(frozen=True)
class Selection:
    """What :func:`regress_kinds` selected: the groups (keys), their joint validated share,
    whether the selection is a pair found by looking two kinds ahead (:func:`_look_ahead`), and
    where it holds two groups or more, their coefficients fitted together."""

    keys: list
    share: float
    looked_ahead: bool = False
    #: two groups or more: each group's coefficients fitted beside the others' (responses' sign)
    coefficients: dict = field(default_factory=dict)


def _one_law(a: str, b: str) -> bool:
    """Whether kinds `a` and `b` together are one kind's law already: one nests the other, or a
    third nests both (Coulomb and viscous friction: ``coulomb_viscous_friction``)."""
    return any({a, b} <= set(kind.nests) | {name} for name, kind in REGISTRY.items())


def _look_ahead(out, responses, fit, sse0, noise, price, parameters, current, sse_now, lawful=None):
    """The best pair of kinds fitted together, where it beats the forward selection; else None.

    The forward selection adds the kind that explains most alone, and a kind that stands in for
    two stops it: a geared pair's viscous friction under a constant torque offset was explained
    96 % by an asymmetric damping (a stiffer damping one way stands in for the offset), what was left
    was under 5 % of the start, and viscous friction and the constant load, which explain it to the
    noise together, were pruned before any fit (compound benchmark, seed 3738, case 025).  So every
    pair of kinds (each kind's best-scored group; not two that are one law,
    :func:`_one_law`) is fitted together too.  The best pair replaces the selection where its
    penalised score is lower (a pair that is not ``lawful``, its coefficients fitted together
    breaking a member's sign, is not tried), it drops the validation SSE below the selection's by
    :data:`MIN_DROP_PER_COLUMN` noise variances per column and by 30 % of what the selection leaves
    above the noise, and each member earns its place beside the other by the same two rules (the
    forward selection's, one kind ahead).  It must also explain :data:`LOOK_AHEAD` of the starting
    excess more than the selection: where the signal is thousands of times the noise, the
    linearisation's own error (:func:`~diagnosis.graph_location_linear.LinearisedResponse`, a
    first-order step) and a sign's shape the features do not match leave tens of noise variances
    per value after the right kind, which a second kind's columns always take up: 0.008 % of the
    start after a viscous friction, 0.02 % after a Coulomb friction at 0.3 N, each under a position
    noise of 1 mm (the feature tests).  A stand-in left 4.5 % (case 025 above); a Coulomb + viscous
    friction beside a constant force, whose response is a small share of a large residual, 0.33 %
    (the feature tests' mass-spring) and 0.39 % (a force-driven carriage: ``python -m
    diagnosis.benchmark.ball_screw``, seed 12, case 005), which 1 % of the start, this threshold
    until session 41, missed.
    Returns ``((key_a, key_b), sse)``.
    """
    best = {}
    for key, row in out.items():
        if key[0] not in best or row[1] < out[best[key[0]]][1]:
            best[key[0]] = key
    cols = {key: responses[key][1].shape[2] for key in best.values()}
    priced = {key: (parameters or {}).get(key, cols[key]) for key in cols}
    trials = []
    for a, b in combinations(best.values(), 2):
        if _one_law(a[0], b[0]) or (lawful is not None and not lawful((a, b))):
            continue
        sse, _ = fit(np.concatenate([responses[a][1], responses[b][1]], axis=2))
        trials.append((sse / sse0 * (1.0 + price) ** (priced[a] + priced[b]), sse, (a, b)))
    if not trials:
        return None
    score, sse, (a, b) = min(trials, key=lambda x: x[0])

    def earns(before, columns):
        return before - sse >= MIN_DROP_PER_COLUMN * columns and before - sse >= 0.3 * max(before - noise, 0.0)

    alone = {key: sse0 * (1.0 - out[key][0]) for key in (a, b)}
    if (score < current and earns(sse_now, cols[a] + cols[b]) and sse_now - sse >= LOOK_AHEAD * (sse0 - noise)
            and earns(alone[a], cols[b]) and earns(alone[b], cols[a])):
        return (a, b), sse
    return None


def _weighted_split(r, w, validation: float, folds=None):
    """``(sw, b, folds)``: the square-root weights of `w`, the weighted residual `r` (rows, ny), and
    each row's validation fold (:func:`regress_kinds`; default the time split: the first rows -1,
    the last `validation` share 0)."""
    if folds is None:
        folds = np.where(np.arange(r.shape[0]) < int(round((1.0 - validation) * r.shape[0])), -1, 0)
    sw = np.sqrt(np.asarray(w, float))
    return sw, r * sw[None, :], np.asarray(folds, int)


def _validated_sse(S, sw, b, folds) -> tuple[float, int]:
    """``(validation SSE, rank)`` of the least-squares fits of the weighted residual `b` (rows, ny) on
    the responses `S` (rows, ny, m), weights `sw`: each fold's rows predicted by the coefficients
    fitted on the other rows, the squared errors summed over the folds (the least rank of the fits)."""
    A = S * sw[None, :, None]
    sse, rank = 0.0, S.shape[2]
    for f in np.unique(folds[folds >= 0]):
        on = folds != f
        A_fit, A_val = A[on].reshape(-1, S.shape[2]), A[~on].reshape(-1, S.shape[2])
        scale = np.sqrt(np.sum(A_fit ** 2, axis=0))
        scale[~(scale > 0)] = 1.0
        coef, _, k, _ = np.linalg.lstsq(A_fit / scale, b[on].reshape(-1), rcond=1e-10)
        err = b[~on].reshape(-1) - (A_val / scale) @ coef
        sse, rank = sse + float(err @ err), min(rank, int(k))
    return sse, rank


def left_with(responses: dict, beside, r, w, *, validation: float = VALIDATION, lost: int = 0, folds=None) -> dict:
    """What each group of `responses` (key -> (names, S)) leaves of the weighted residual `r`
    (rows, ny; weights `w`, 1/sigma^2) with the columns `beside` (rows, ny, m) fitted alongside:
    the validation rows' mean squared weighted error (the same time split as
    :func:`regress_kinds`), in noise variances (about 1 where only the noise is left; `lost` and
    `folds` as for :func:`regress_kinds`); NaN for a group whose responses are not finite.

    Examples
    --------
    A residual made of two columns' responses and unit noise: either column alone leaves part of
    it, each with the other beside it only the noise:

    >>> rng = np.random.default_rng(0)
    >>> a, b = rng.standard_normal((2, 2000, 1, 1))
    >>> r = (3 * a + 2 * b)[:, :, 0] + rng.standard_normal((2000, 1))
    >>> {k: round(v, 1) for k, v in left_with({"a": ([], a)}, b, r, np.ones(1)).items()}
    {'a': 1.0}
    """
    rows = r.shape[0]
    sw, b, folds = _weighted_split(r, w, validation, folds)
    n_val = int(np.count_nonzero(folds >= 0)) * r.shape[1]
    out = {}
    for key, (_, S) in responses.items():
        ok = np.isfinite(S).all() and S.shape[0] == rows and n_val
        out[key] = (_validated_sse(np.concatenate([S, beside], axis=2), sw, b, folds)[0] / max(n_val - lost, 1)
                    if ok else float("nan"))
    return out


def feature_evidence(graph, places, experiment, *, x0=None, regime_variables=None, estimates=None,
                     restart: int | None = None) -> dict:
    """The feature regression (module docstring) at each junction place of `places`.

    The features and the linearised responses are taken along the *corrected* run: the
    model with the location's estimate :math:`\\hat d` injected at the junction (close to
    the plant where the missing effect is strong, as a cubic spring that halves the
    motion), and the residual regressed is the linearised nominal one,
    :math:`r_c + S_c \\hat d \\approx S_c F \\beta` (a Gauss-Newton step from the estimate).
    Without an estimate the run is the nominal one.

    Parameters
    ----------
    graph : BondGraph
        The nominal model.
    places : iterable of Place
        Places; inputs and outputs are skipped (they keep their own structured corrections); a
        law place is regressed at the junction that splits its bond (:mod:`diagnosis.law_places`).
    experiment : Experiment
        The part of the recording the location ran on (model units).
    x0 : dict str -> float, optional
        State at its first sample.
    regime_variables : dict, optional
        From :func:`diagnosis.locate.regime_variables`: which signals may modulate a friction.
    estimates : dict Place -> ndarray, optional
        The location's estimated extra effort / flow per junction at the experiment's
        times (``PlaceScore.estimate``; NaN outside its window counts as 0).
    restart : int, optional
        Under the segment judge (a drifting nominal), its segments' length in samples: the
        regression fits every segment's start state too (:mod:`diagnosis.feature_restarts`).

    Returns
    -------
    dict Place -> FeatureEvidence
        Places whose run or linearisation fails are left out.
    """
    out = {}
    for p in places:
        if p.kind not in ("junction", "law") or not experiment.outputs:
            continue
        d_hat = next((e for q, e in (estimates or {}).items() if (q.kind, q.name) == (p.kind, p.name)), None)
        try:
            at_graph, at = at_junction(graph, p)     # a law: the junction that splits its bond
            ev = _evidence_at(at_graph, at, experiment, x0, regime_variables, d_hat, restart)
        except (BondcosimError, FloatingPointError, np.linalg.LinAlgError, ValueError):
            ev = None
        if ev is not None:
            ev.place = p
            out[p] = ev
    return out


def _evidence_at(graph, p, experiment, x0, regime_variables, d_hat, restart=None):
    """:func:`feature_evidence` at one junction place (None when a run is not finite)."""
    from bondgraph.io_json import graph_from_dict

    from .catalogue_common import ambient_effort, junction_domain
    from .graph_location_graph import corrected, junction_unit
    from .graph_location_linear import LinearisedResponse
    from .residuals import OutputSimulator, noise_sigma

    outputs = list(experiment.outputs)
    aug, exp, d = corrected(graph, experiment, p.name, d_hat)
    d_hat = exp.inputs[d]
    signals = _signals(graph, p.name, regime_variables)
    if graph.elements[p.name].kind == "1":
        aug, signals["travel"] = _with_travel(aug, p.name)
    data = aug.to_dict()
    labels = {}
    for label, expr in signals.items():
        key = f"feature_{len(labels)}"
        labels[key] = label
        data["outputs"].append({"name": key, "expression": str(expr), "unit": ""})
    aug = graph_from_dict(data, source=f"features of {graph.name}")
    sim = OutputSimulator(aug, exp, outputs=outputs + list(labels))
    run = sim.run(None, x0)
    t = run.t
    n = t.size
    measured = {o: np.asarray(experiment.outputs[o], float) for o in outputs}
    residual = {o: measured[o] - run.outputs[o] for o in outputs}
    values = {label: np.asarray(run.outputs[key], float) for key, label in labels.items()}
    if d_hat.size == t.size:            # the estimate itself: a kind may read its grid off it
        values["estimate"] = d_hat
    if not all(np.isfinite(v).all() for v in list(residual.values()) + list(values.values())):
        return None
    lin = LinearisedResponse(sim.model, run, sim.model.param_vector(None), [d], outputs)
    rows = np.arange(0, n, max(1, int(np.ceil(n / _MAX_ROWS))))
    # the weights from the nominal residual's noise, as the location's
    sigma = [max(noise_sigma(measured[o], residual[o]), 1e-3 * float(np.std(measured[o])), 1e-300)
             for o in outputs]
    w = 1.0 / np.square(sigma)
    # one set of signals for every kind (its cached sign and RMS flow computed once)
    one = graph.elements[p.name].kind == "1"
    signals = FeatureSignals(np.asarray(t, float), values, one, junction_domain(graph, p.name),
                             None if one else ambient_effort(graph, p.name, values.get("effort")))
    groups, grids = {}, {}
    for kind in [name for name, definition in REGISTRY.items() if definition.feature_doors]:
        for group in _kind_variants(kind, signals):
            groups[(kind, group.variant, group.detail)] = (group.names, group.columns)
            grids[(kind, group.variant, group.detail)] = tuple(group.grid)
    if not groups:
        return None
    keys = list(groups)
    own = value_columns(graph, p.name, signals)
    beside = [] if own is None else [own.columns]
    F_all = np.concatenate([d_hat[:, None]] + [groups[k][1] for k in keys] + beside, axis=1)
    S_all = lin.response(np.zeros(F_all.shape[1], dtype=int), F_all, rows)
    r = np.stack([residual[o][rows] for o in outputs], axis=1) + S_all[:, :, 0]   # linearised nominal residual
    lost, folds = 0, None
    if restart:          # a drifting nominal: each segment's own start state is a free nuisance
        r, S_all, lost, folds = restarted(lin, rows, restart, r, S_all, np.sqrt(w))
    edges = 1 + np.cumsum([0] + [groups[k][1].shape[1] for k in keys])
    responses = {k: (groups[k][0], S_all[:, :, a:b]) for k, a, b in zip(keys, edges[:-1], edges[1:])}
    prices = {k: REGISTRY[k[0]].feature_price for k in keys}
    signs = {k: REGISTRY[k[0]].feature_signs for k in keys}
    ranked, selection = regress_kinds(responses, r, w, parameters=prices, lost=lost, folds=folds, signs=signs)
    with_values = left_with(responses, S_all[:, :, edges[-1]:], r, w, lost=lost, folds=folds) if beside else {}

    def evidence(key, beta):        # the catalogue's sign: an element that takes effort or flow
        share, score, _, sig, excess, drop = ranked[key]
        return KindEvidence(*key, float(share), float(score), {nm: -float(c) for nm, c in zip(responses[key][0], beta)},
                            sig, excess, float(drop), grids[key], with_values.get(key, float("nan")))

    best = {}
    for key, (_, score, beta, *_rest) in ranked.items():
        if key[:2] not in best or score < best[key[:2]].score:
            best[key[:2]] = evidence(key, beta)
    kinds = sorted(best.values(), key=lambda k: k.score)
    chosen = [f"{k[0]} ({k[1]})" if k[1] else k[0] for k in selection.keys]
    together = [evidence(key, beta) for key, beta in selection.coefficients.items()]
    return FeatureEvidence(p, kinds, chosen, float(selection.share), junction_unit(graph, p.name),
                           selection.looked_ahead, together)


#: pruning (on the validated shares of the residual beyond the noise): only where the best
#: kind's features explain at least this share ...
PRUNE_FROM = 0.5
#: ... a candidate whose kind's features leave more than PRUNE_FACTOR times what the best
#: leave unexplained, and more than PRUNE_FLOOR of the residual, is not fitted (the
#: PRUNE_KEEP best kinds always are)
PRUNE_FACTOR, PRUNE_FLOOR, PRUNE_KEEP = 10.0, 0.25, 3
#: a near-tie in :func:`diagnosis.fit.choose` goes to another kind when its features leave at
#: most this share of what the default winner's leave unexplained beyond the noise (and drop the
#: weighted SSE by :data:`MIN_DROP_PER_COLUMN` noise variances more)
PREFER_RATIO = 0.5


def evidence_lookup(evidence: dict):
    """``fit_or_candidate -> KindEvidence or None`` over the evidence of several places."""
    def lookup(item):
        cand = getattr(item, "candidate", item)
        place = getattr(cand, "place", None)
        if place is None:
            return None
        for ev in evidence.values():
            if (ev.place.kind, ev.place.name) == (place.kind, place.name):
                return ev.for_candidate(cand)
        return None
    return lookup


def prune_candidates(cands: list, evidence: dict) -> tuple[list, list]:
    """The candidates worth a fit by simulation, and those the feature evidence rules out.

    At a place whose best significant kind explains at least :data:`PRUNE_FROM` of the
    residual, a candidate with features is dropped when it is not among the
    :data:`PRUNE_KEEP` best and its features leave more than :data:`PRUNE_FACTOR` times
    the best's unexplained share (beyond the noise) and more than :data:`PRUNE_FLOOR`.  Candidates without
    features (inputs, outputs, heat transfer, twins) are always kept, and so is a richer law that
    nests the best kind (:attr:`Kind.nests <diagnosis.kinds.base.Kind.nests>`: a pressure-dependent
    friction, whose constant term is the Coulomb level): fitted by simulation it does at least as
    well, and its features' validation is on the record's last rows only (:func:`regress_kinds`),
    where its extra term may meet values the first rows never had.  A cylinder's pressure held at
    other levels in the last rows than in the first made the pressure term's fit on the first rows
    collinear with the sign: it validated at -124 % with coefficients on all rows equal to the
    truth's, and Coulomb friction answered (seed 2323, case 023).  The kind that leaves least with
    the junction's values beside it (:meth:`FeatureEvidence.best_with_values`) is kept too, to be
    refitted beside them (:func:`diagnosis.pairs.value_pairs`): a carriage's hardening spring
    validated at -990 % alone, its linear term standing in for a mass 3 % light, and at the noise
    with the mass beside it (detuned benchmark, seed 7474, case 035).  So is a kind of the
    :attr:`FeatureEvidence.selected`: a constant load that explains 3 % alone and, beside a viscous
    friction, the rest (:func:`regress_kinds`' look-ahead).  A kind that
    :attr:`~diagnosis.kinds.base.Kind.needs_evidence` is fitted only where its features are
    significant and among the :data:`PRUNE_KEEP` best.
    """
    keep, dropped = [], []
    for cand in cands:
        place = getattr(cand, "place", None)
        place_ev = next((e for e in evidence.values() if place is not None
                         and (e.place.kind, e.place.name) == (place.kind, place.name)), None)
        ev = place_ev.for_candidate(cand) if place_ev is not None else None
        best = place_ev.best() if place_ev is not None else None
        if getattr(REGISTRY.get(getattr(cand, "kind", None)), "needs_evidence", False) and not (
                ev is not None and ev.significant and ev in place_ev.kinds[:PRUNE_KEEP]):
            dropped.append(cand)        # a law flexible enough to stand in for others: only on its evidence
            continue
        if (ev is None or best is None or best.excess_share < PRUNE_FROM or ev in place_ev.kinds[:PRUNE_KEEP]
                or ev.label in place_ev.selected):
            keep.append(cand)
            continue
        if best.kind in getattr(REGISTRY.get(cand.kind), "nests", {}) or ev is place_ev.best_with_values():
            keep.append(cand)
            continue
        left, best_left = 1.0 - ev.excess_share, max(1.0 - best.excess_share, 0.0)
        (dropped if left > max(PRUNE_FACTOR * best_left, PRUNE_FLOOR) else keep).append(cand)
    return keep, dropped


def with_feature_starts(cands: list, evidence: dict) -> list:
    """`cands`, each with one more start where its kind's feature coefficients estimate its
    leading parameters (``Kind.feature_params``: a Coulomb level from ``sign(v)``, a viscous
    coefficient from ``v``, a leak conductance from ``e - P_amb``), clipped to their bounds.

    The catalogue's guesses scale with the junction's effort (10 % of it for a friction level);
    a friction a million times smaller (a frictionless joint's seal) starts decades away from
    them, where the fit stalls and is given up (:mod:`diagnosis.fit_in_turn`).  The regression
    on the located estimate has already measured the level."""
    lookup = evidence_lookup(evidence)

    def started(cand):
        kind = getattr(cand, "definition", None)            # a group of twins has none
        ev = lookup(cand) if kind is not None else None
        return cand if ev is None else with_feature_start(cand, ev)

    return [started(c) for c in cands]


def with_feature_start(cand, evidence, first: bool = False):
    """`cand` with its bounds admitting `evidence`'s coefficients (:func:`admitting`) and one more
    start there (``Kind.feature_start``): after its own starts, or before them (`first`)."""
    cand = admitting(cand, evidence)
    start = cand.definition.feature_start(cand, evidence)
    if not start:
        return cand
    return replace(cand, starts=(start,) + tuple(cand.starts)) if first else cand.with_starts([start])


#: a bound a significant feature coefficient lies beyond is moved to this many times it
ADMIT = 2.0


def admitting(cand, evidence):
    """`cand` with the bounds of its leading parameters (``Kind.feature_params``) widened to
    :data:`ADMIT` times their feature coefficients where those lie beyond them, on the bound's own
    side of zero (a bound at zero is the law's sign), and the kind's features are significant
    (`evidence`, a :class:`KindEvidence`).  A kind's bounds are a multiple
    of the junction's efforts in the nominal run, and a load those efforts never meet may be
    larger: a DC motor's load shaft, whose nominal torques are its inertia's and damper's, 0.03 N m,
    carried a constant load of 0.46 N m, clipped at the constant load's 0.29 N m bound in every fit
    (ball-screw benchmark, seed 12, case 008).  The located estimate has measured it."""
    kind = cand.definition
    n = kind.feature_params
    if not n or not evidence.significant:
        return cand
    params = list(cand.params)
    for i, name in enumerate(kind.feature_names[:n]):
        c = evidence.coefficients.get(name)
        if i >= len(params) or c is None or not np.isfinite(c):
            continue
        spec = params[i]        # a bound at zero is the law's sign (a friction takes energy): kept
        if c > spec.upper > 0:
            params[i] = replace(spec, upper=ADMIT * c)
        elif c < spec.lower < 0:
            params[i] = replace(spec, lower=ADMIT * c)
    return replace(cand, params=type(cand.params)(params)) if params != list(cand.params) else cand


def prefer_by_evidence(default, near: list, lookup):
    """Among `near` (fits within a parameter's price of the best held-out score), the fit the
    feature evidence prefers to `default`, or `default`.

    Another kind is preferred only when both have evidence, its features are significant,
    leave at most :data:`PREFER_RATIO` of what `default`'s leave unexplained beyond the
    noise and drop the weighted SSE by :data:`MIN_DROP_PER_COLUMN` noise variances more;
    among such, the lowest penalised feature score.  `default`'s kind is credited with the best
    evidence (lowest score) it has at any place among `near`: the question is which kind, and
    series springs are located alike.  A cubic spring in the exoskeleton's gear, fitted there,
    had features explaining 64 % at the gear, while the same kind at the trunk coupling, as
    near in held-out error, explained 99 %; an end stop at the coupling (97 %) was preferred to
    it (seed 6060, case 037).
    """
    own = [lookup(f) for f in [default] + list(near)
           if f.candidate is not None and f.candidate.kind == default.candidate.kind]
    own = [ev for ev in own if ev is not None]
    if not own:
        return default
    base = min(own, key=lambda ev: ev.score)
    better = []
    for f in near:
        ev = lookup(f)
        if (f is default or ev is None or not ev.significant or f.candidate.kind == default.candidate.kind
                or ev.drop - base.drop < MIN_DROP_PER_COLUMN
                or 1.0 - ev.excess_share > PREFER_RATIO * (1.0 - base.excess_share)):
            continue
        better.append((ev.score, f))
    return min(better, key=lambda x: x[0])[1] if better else default
