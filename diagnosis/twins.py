"""Effects shared by identical components: the same kind at every twin of a place.

Machines repeat their parts: two muscles with two chambers fed by two valves of one type, the
joints of an arm, the pressure sensors of one make.  A physical cause often acts on all of them
at once (both chambers leak, both valves answer late, every sensor reads low), and then no
single place explains the recording: a fit at one place only is pulled between its own output
and the outputs the other copies disturb.  So a promising single-place fit is also tried at all
of the place's twins together, each copy with its own parameters, and the held-out error
decides as for any candidate (the extra parameters pay the same price there).

Twins (:func:`twin_places`) are places of the same kind that look the same on the graph:

* junctions of the same type (0 or 1) and energy domain whose bonded elements are of the same
  kinds (``chamber1`` and ``chamber2`` of the PAM joint: each a 0-junction between a valve MSf
  and a pneumatic chamber);
* law places (:mod:`diagnosis.law_places`) of elements of the same kind, at the same port,
  setting the same variable (the force laws of the two muscles);
* recorded inputs with the same unit (the valve voltages);
* measured outputs with the same unit (the two pressure sensors).
"""
from __future__ import annotations

from dataclasses import dataclass, replace

from .catalogue_common import priced
from .place import Place

__all__ = ["CandidateGroup", "twin_places", "twin_groups", "idle_members", "without_idle_members", "IDLE"]

#: a member of a group whose magnitudes all end at most this share of their guesses adds nothing
IDLE = 1e-6


@dataclass(frozen=True)
class CandidateGroup:
    """One kind at several twin places at once (each member keeps its own parameters).

    It answers what :class:`~diagnosis.catalogue.Candidate` answers, so the fit and the choice
    treat it as one candidate; the report lists one effect per member.
    """

    members: tuple

    @property
    def kind(self) -> str:
        return self.members[0].kind

    @property
    def place(self) -> Place:
        """The first member's place (where the located correction and the regime are read)."""
        return self.members[0].place

    @property
    def places(self) -> tuple:
        return tuple(m.place for m in self.members)

    @property
    def params(self) -> list:
        return [p for m in self.members for p in m.params]

    @property
    def initial(self) -> dict:
        return {k: v for m in self.members for k, v in m.initial.items()}

    @property
    def starts(self) -> tuple:
        """The members' alternative starts side by side (the i-th of each that has one)."""
        depth = max((len(m.starts) for m in self.members), default=0)
        return tuple({k: v for m in self.members if i < len(m.starts) for k, v in m.starts[i].items()}
                     for i in range(depth))

    @property
    def n_params(self) -> int:
        return priced(self.params)

    def guesses(self) -> dict:
        return {p.name: p.guess for p in self.params}

    def _split(self, values) -> list[dict]:
        values = dict(values or {})
        return [{p.name: values[p.name] for p in m.params if p.name in values} for m in self.members]

    def values_with_guesses(self, values=None) -> dict:
        out = {}
        for member, own in zip(self.members, self._split(values)):
            out.update(member.values_with_guesses(own))
        return out

    def settle(self, values: dict, experiment) -> dict:
        out = dict(values)
        for member, own in zip(self.members, self._split(values)):
            out.update(member.settle(own, experiment))
        return out

    def build(self, model_graph, values=None):
        """`model_graph` with the effect at every member's place (one after the other)."""
        graph = model_graph
        for member, own in zip(self.members, self._split(values)):
            graph = member.build(graph, own)
        return graph

    def explain(self, values=None) -> str:
        return "; ".join(m.explain(own) for m, own in zip(self.members, self._split(values)))

    def with_members(self, transform) -> "CandidateGroup":
        """A group whose members are ``transform(member)``."""
        return replace(self, members=tuple(transform(m) for m in self.members))

    def __str__(self) -> str:
        return f"{self.kind} at {', '.join(map(str, self.places))}"


def _signature(graph, place: Place, experiment):
    """What a twin of `place` must share (None: a place that has no twins)."""
    if place.kind == "junction":
        from .catalogue_common import junction_domain, junction_elements
        neighbours = tuple(sorted(el.kind for el, _ in junction_elements(graph, place.name)))
        return graph.elements[place.name].kind, junction_domain(graph, place.name), neighbours
    if place.kind == "law":
        from .law_places import law_port
        port = law_port(graph, place)
        return "law", graph.elements[port.element].kind, port.port, port.sets
    if place.kind == "input":
        units = {d.name: d.unit for d in graph.inputs()}
    else:
        units = {name: getattr(out, "unit", "") for name, out in graph.outputs.items()}
    return place.kind, units.get(place.name, "")


def twin_places(graph, place: Place, places, experiment=None) -> list[Place]:
    """The places among `places` (other than `place`) that look like `place` on `graph`."""
    mine = _signature(graph, place, experiment)
    return [p for p in places if p.kind == place.kind and p.name != place.name
            and _signature(graph, p, experiment) == mine]


def twin_groups(graph, fits, all_places, make_candidates, *, experiment=None, best: int = 3) -> list[CandidateGroup]:
    """Groups for the `best` successful single-place fits (lowest held-out error) that have twins.

    `make_candidates(place)` lists the catalogue's candidates at a place; a twin joins the group
    with its candidate of the same kind (and the same target element kind, if any).
    """
    from .fit import single_fits_by_holdout

    groups, seen = [], set()
    for fit in single_fits_by_holdout(fits):
        if len(groups) >= best:
            break
        cand = fit.candidate
        twins = twin_places(graph, cand.place, all_places, experiment)
        if not twins or (cand.kind, cand.place) in seen:
            continue
        members = [cand]
        for twin in twins:
            same = [c for c in make_candidates(twin) if c.kind == cand.kind and c.regime == cand.regime
                    and (c.target is None) == (cand.target is None)]
            if same:
                members.append(same[0])
        if len(members) > 1:
            groups.append(CandidateGroup(tuple(members)))
            seen |= {(cand.kind, m.place) for m in members}
    return groups


def idle_members(group: CandidateGroup, values: dict) -> list[int]:
    """The indices of `group`'s members whose magnitudes (:attr:`ParamSpec.magnitude
    <diagnosis.catalogue_common.ParamSpec.magnitude>`) all ended at most :data:`IDLE` of their
    guesses in `values`; a member without magnitudes is never idle."""
    idle = []
    for i, member in enumerate(group.members):
        magnitudes = [p for p in member.params if p.magnitude]
        if magnitudes and all(abs(values.get(p.name, p.guess)) <= IDLE * p.guess for p in magnitudes):
            idle.append(i)
    return idle


def without_idle_members(fit, graph):
    """`fit` (a :class:`~diagnosis.fit.CandidateFit`) answered by the members of its group that act:
    the group of the others, or the one other candidate, with their values, their priced
    parameters and their graph built on `graph`.  Its errors stay: an idle member predicts nothing
    (its effect is at most :data:`IDLE` of its guess).  A fit whose members all act, or all idle,
    or that is not of a group, is returned as it is.  A group fitted at the twins of a located
    chamber put the whole leak at the other chamber (the truth's value to three digits) and
    9.9e-20 at the located one, which the answer then named first (seed 2929, case 004)."""
    group = fit.candidate
    if not isinstance(group, CandidateGroup) or not fit.success:
        return fit
    idle = idle_members(group, fit.values)
    if not idle or len(idle) == len(group.members):
        return fit
    active = tuple(m for i, m in enumerate(group.members) if i not in idle)
    dropped = [p for i in idle for p in group.members[i].params]
    names = {p.name for p in dropped}
    candidate = active[0] if len(active) == 1 else CandidateGroup(active)
    return replace(fit, candidate=candidate, values={k: v for k, v in fit.values.items() if k not in names},
                   n_params=fit.n_params - priced(dropped), graph=candidate.build(graph),
                   extra={**fit.extra, "idle_twins": [str(group.members[i].place) for i in idle]})
