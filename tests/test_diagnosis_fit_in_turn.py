"""diagnosis.fit_in_turn: a fit whose training cost stays far above the best so far is given up;
the answers are those of fitting every candidate fully (an invariance, on recordings of the
hand-written truth of test_diagnosis_pipeline)."""
import numpy as np
import pytest

import diagnosis.fit_in_turn as fit_in_turn
from diagnosis.diagnose import diagnose
from test_diagnosis_pipeline import BINDINGS, FC, _recording


def _answers(report):
    return [(m["kind"], m["attached_to"], m["parameters"]) for m in report.to_json()["missing_physics"]]


@pytest.mark.parametrize("fc, offset, seed", [(0.0, 0.2, 13), (FC, 0.02, 14)])
def test_giving_up_hopeless_fits_changes_no_answer(tmp_path, monkeypatch, fc, offset, seed):
    """A sensor offset alone (0.2 m), and Coulomb friction with a 20 mm offset (two rounds):
    the same effects, values and held-out NRMSE with and without giving up; with it, some fits
    are given up and fewer simulations run."""
    path = str(_recording(tmp_path / "rec.csv", fc, seed, offset))
    quick = diagnose("mass-spring-damper", path, **BINDINGS)
    monkeypatch.setattr(fit_in_turn, "HOPELESS", np.inf)
    full = diagnose("mass-spring-damper", path, **BINDINGS)
    assert [a[:2] for a in _answers(quick)] == [a[:2] for a in _answers(full)]
    for (_, _, fast), (_, _, slow) in zip(_answers(quick), _answers(full)):
        assert fast == pytest.approx(slow, rel=1e-9)
    assert quick.fit["improved"] == pytest.approx(full.fit["improved"], rel=1e-9)
    fits = [f for r in quick.rounds for f in r.fits]
    given_up = [f for f in fits if f.extra.get("abandoned")]
    assert given_up and all(not f.success for f in given_up)
    assert not any(f.extra.get("abandoned") for r in full.rounds for f in r.fits)
    sims = lambda report: sum(f.n_simulations for r in report.rounds for f in r.fits)   # noqa: E731
    assert sims(quick) < sims(full)
    assert "given up early" in quick.text


def test_each_fit_gets_ten_times_the_best_training_cost_so_far():
    """The threshold passed to each fit: none before a successful fit, then HOPELESS x the best."""
    from types import SimpleNamespace
    seen = []
    costs = {"a": 0.5, "b": 0.1, "c": 2.0, "d": 0.05}

    def fit(cand, abandon_above):
        seen.append(abandon_above)
        return SimpleNamespace(success=cand != "c", extra={"train_cost": costs[cand]}, n_simulations=1,
                               holdout_nrmse={"x": 0.1}, message="")

    fits, best = fit_in_turn.fit_in_turn(["a", "b", "c", "d"], fit, lambda *a: None, "fitting")
    assert seen == [None, pytest.approx(5.0), pytest.approx(1.0), pytest.approx(1.0)]
    assert best == 0.05 and len(fits) == 4


def test_a_richer_friction_starts_where_the_coulomb_fit_it_extends_ended():
    """Coulomb + viscous, Stribeck, pressure-dependent and modulated friction extend Coulomb
    friction: each starts at the fitted Coulomb level with its extra terms at zero, where its law
    IS the fitted Coulomb law (same simulated output), so it starts no worse than that fit."""
    from types import SimpleNamespace

    import plants
    from bondgraph.numerics import simulate
    from diagnosis.catalogue import candidates
    from diagnosis.place import Place

    msd = plants.load("mass-spring-damper")
    at = {c.kind: c for c in candidates(msd, Place("junction", "v_mass"))}
    coulomb = at["coulomb_friction"]
    fitted = {coulomb.params[0].name: 0.3}
    done = [SimpleNamespace(candidate=coulomb, success=True, values=fitted)]

    def x(graph, values):
        return simulate(graph, (0.0, 4.0), inputs={"F": lambda s: 2.0 if s < 2.0 else -1.0},
                        params=values, output_interval=0.01)["x"]

    reference = x(coulomb.build(msd, fitted), None)
    extending = [k for k in at if "coulomb_friction" in at[k].definition.nests]
    assert extending == ["stribeck_friction", "coulomb_viscous_friction"]    # those offered on the msd
    for kind in extending:
        richer = at[kind]
        warmed = fit_in_turn.nested_starts(richer, done)
        start, *more = [s for s in warmed.starts if s not in richer.starts]
        assert start[richer.params[0].name] == 0.3
        if kind == "stribeck_friction":     # and at that level with peaks, decays and sharper signs
            fc, dfs, vs, eps = (p.name for p in richer.params)
            assert len(more) == 12 and all(s[fc] == 0.3 for s in more)
            assert sorted({s[dfs] for s in more}) == pytest.approx([0.15, 0.3, 0.6])
            assert len({s[vs] for s in more}) == 2 and max(s[eps] for s in more) < start[eps] * 1.0001
        else:
            assert more == []
        # the same law: the outputs agree to the integrator's tolerance
        assert np.max(np.abs(x(richer.build(msd, start), None) - reference)) < 1e-6 * np.ptp(reference)
    # a kind that extends nothing, and one fitted at another place, get no such start
    assert fit_in_turn.nested_starts(at["hysteresis"], done) is at["hysteresis"]
    elsewhere = [SimpleNamespace(candidate=coulomb, success=True, values=fitted)]
    other = candidates(msd, Place("junction", "v_mass"))[0]
    assert other.kind == "coulomb_friction" and fit_in_turn.nested_starts(other, elsewhere) is other


def _msd_coulomb_fits():
    """The mass-spring-damper under a 0.3 N Coulomb friction: ``(fit_at, calls, fit)``.
    ``fit_at(kind, max_nfev=None)`` fits the candidate of `kind` at the mass's junction (a sensor
    offset at output x), one stopped after `max_nfev` evaluations taken as converged;
    ``fit(cand, abandon_above)``, as fit_in_turn calls it, fits fully and appends each candidate to
    `calls`."""
    from dataclasses import replace

    from diagnosis.catalogue import candidates
    from diagnosis.fit import fit_candidate
    from diagnosis.place import Place
    from plants.library.textbook import mass_spring_damper
    from test_diagnosis_fit import _record, coulomb_truth

    msd = mass_spring_damper()
    train, hold = _record(coulomb_truth()).split(0.3)
    at = {c.kind: c for c in candidates(msd, Place("junction", "v_mass"), experiment=train)}
    at["sensor_offset"] = next(c for c in candidates(msd, Place("output", "x"), experiment=train)
                               if c.kind == "sensor_offset")
    calls = []

    def fit_at(kind, max_nfev=None):
        if max_nfev is None:
            return fit_candidate(msd, at[kind], train, hold)
        return replace(fit_candidate(msd, at[kind], train, hold, max_nfev=max_nfev), success=True)

    def fit(cand, abandon_above):
        calls.append(cand)
        return fit_candidate(msd, cand, train, hold)

    return fit_at, calls, fit


def test_a_simpler_fit_is_refitted_from_where_a_richer_one_ended():
    """A Coulomb fit stopped early (two evaluations, taken as converged: a local minimum) ends far
    from the truth; the Coulomb + viscous fit
    reaches it with its viscous term near 0. Refitted from the richer fit's level and smoothing,
    the Coulomb law matches it (the truth's 0.3 N, smoothed over 0.02 m/s) and replaces the short
    fit; the richer fit and a fit of another place are left as they were."""
    fit_at, calls, fit = _msd_coulomb_fits()
    short = fit_at("coulomb_friction", max_nfev=2)
    richer, other = fit_at("coulomb_viscous_friction"), fit_at("sensor_offset")
    assert richer.extra["train_cost"] < short.extra["train_cost"]
    out = fit_in_turn.simpler_refits([short, richer, other], fit, lambda *a: None, "fitting")
    assert len(calls) == 1 and calls[0].kind == "coulomb_friction"
    assert calls[0].starts[-1] == {"Fc_v_mass": richer.values["Fc_v_mass"],
                                   "v_eps_v_mass": richer.values["v_eps_v_mass"]}
    assert out[1] is richer and out[2] is other and out[0] is not short
    assert out[0].values["Fc_v_mass"] == pytest.approx(0.3, rel=1e-3)
    assert out[0].values["v_eps_v_mass"] == pytest.approx(0.02, rel=1e-2)


def test_a_richer_fit_is_refitted_from_where_a_simpler_one_it_extends_ended():
    """A Coulomb + viscous fit stopped early (two evaluations from its own guess, taken as converged)
    ends above the Coulomb fit's training cost, so the choice would drop it as idle terms.  Refitted
    from the Coulomb fit's level and smoothing with no viscous term, it ends no worse than that fit
    (the truth is a Coulomb friction of 0.3 N); the Coulomb fit and a fit of another place are left
    as they were, and a richer fit already below the simpler one is not refitted."""
    fit_at, calls, fit = _msd_coulomb_fits()
    coulomb, other = fit_at("coulomb_friction"), fit_at("sensor_offset")
    short = fit_at("coulomb_viscous_friction", max_nfev=2)
    assert short.extra["train_cost"] > 2 * coulomb.extra["train_cost"]
    out = fit_in_turn.richer_refits([coulomb, short, other], fit, lambda *a: None, "fitting")
    assert len(calls) == 1 and calls[0].kind == "coulomb_viscous_friction"
    assert calls[0].starts[-1] == {"Fc_v_mass": coulomb.values["Fc_v_mass"], "b_visc_v_mass": 0.0,
                                   "v_eps_v_mass": coulomb.values["v_eps_v_mass"]}
    assert out[0] is coulomb and out[2] is other and out[1] is not short
    assert out[1].extra["train_cost"] <= coulomb.extra["train_cost"] * (1 + 1e-6)
    assert out[1].values["Fc_v_mass"] == pytest.approx(0.3, rel=1e-2)
    # the refit in place: nothing more to do
    assert fit_in_turn.richer_refits(out, fit, lambda *a: None, "fitting") == out and len(calls) == 1
