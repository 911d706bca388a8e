"""The restarted feature regression (diagnosis.feature_restarts): every segment's start state a
nuisance, on a double integrator whose transitions are known in closed form, and on a force-driven
carriage (m v' = F - d(v), x' = v) integrated by the tests' own RK4 (msd_truth.rk4_states), not bondgraph's."""
from types import SimpleNamespace

import numpy as np
import pytest

from diagnosis.feature_restarts import FOLDS, free_responses, restarted
from diagnosis.features import feature_evidence, regress_kinds
from diagnosis.place import Place
from diagnosis.recording import Experiment
from msd_truth import rk4_states


def _double_integrator(n, h):
    """A linearisation stand-in: x' = v, v' = 0 sampled every `h` s, both states measured."""
    Phi = np.repeat(np.array([[[1.0, h], [0.0, 1.0]]]), n - 1, axis=0)
    return SimpleNamespace(C=np.repeat(np.eye(2)[None], n, axis=0), Phi=Phi, n_states=2)


def test_free_responses_are_the_transitions_from_each_segments_start():
    h, lin = 0.1, _double_integrator(10, 0.1)
    N = free_responses(lin, np.arange(0, 10, 2), [0, 6])
    # row 2 (sample 4) is 4 steps into the first segment, row 4 (sample 8) 2 into the second
    np.testing.assert_allclose(N[2], [[1.0, 4 * h], [0.0, 1.0]])
    np.testing.assert_allclose(N[4], [[1.0, 2 * h], [0.0, 1.0]])
    np.testing.assert_allclose(N[3], np.eye(2))         # sample 6: a segment's start


def test_projection_leaves_the_features_response_and_the_noise():
    """A residual of arbitrary drift (each segment's own start state, free responses) plus one
    feature's response and noise (weighted to unit variance): after the projection least squares recovers the feature's
    coefficient, what is left is the noise less the start states' degrees of freedom, and the
    segments are dealt round into FOLDS folds."""
    rng = np.random.default_rng(3)
    n, h, length = 600, 0.01, 50
    lin = _double_integrator(n, h)
    rows = np.arange(n)
    starts = np.arange(0, n, length)
    N = free_responses(lin, rows, starts)
    drift = np.einsum("rij,rj->ri", N, np.repeat(rng.normal(0, 50, (starts.size, 2)), length, axis=0))
    t = rows * h
    # a column curved within the segments, on both outputs
    S = np.stack([np.sin(2 * np.pi * t / 0.2), np.cos(2 * np.pi * t / 0.3)], axis=1)[:, :, None]
    r = drift + 2.5 * S[:, :, 0] + rng.normal(0, 0.1, (n, 2))
    rp, Sp, lost, folds = restarted(lin, rows, length, r, S, np.full(2, 10.0))
    assert lost == 2 * starts.size
    assert list(folds[::length]) == [i % FOLDS for i in range(starts.size)]
    beta = np.linalg.lstsq(Sp.reshape(-1, 1), rp.reshape(-1), rcond=None)[0][0]
    assert beta == pytest.approx(2.5, rel=0.02)
    left = rp - beta * Sp[:, :, 0]
    assert float(np.sum(left ** 2)) / 0.1 ** 2 == pytest.approx(r.size - lost, rel=0.1)


def test_regress_kinds_validates_across_folds():
    """With folds, every fold is predicted by the coefficients fitted on the others: a column that
    is the residual everywhere explains it whatever the order of the rows, and a column that only
    lives in one fold explains nothing there."""
    rng = np.random.default_rng(0)
    x = rng.normal(0, 1, (300, 1, 1))
    r = 3.0 * x[:, :, 0] + rng.normal(0, 0.1, (300, 1))
    folds = np.arange(300) % 3
    lone = np.where((folds == 0)[:, None, None], x, 0.0)
    ranked, _ = regress_kinds({("a", None, ""): (["x"], x), ("b", None, ""): (["x"], lone)}, r, np.ones(1) / 0.01,
                              folds=folds)
    assert ranked[("a", None, "")][0] > 0.99
    assert ranked[("b", None, "")][0] < 0.7


def _carriage(seed, fc=1.0, b=4.0, load=1.5, m=20.0, fs=200.0, span=7.0, eps=0.008):
    """x, v of the carriage m v' = F - fc tanh(v/eps) - b v - load (RK4, ten steps per sample, F
    held), with noise of 10 mm and 2 mm/s; F levels that change every 0.7 s plus a sine, about a
    bias that drives the carriage mostly one way."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, span, 1.0 / fs)
    levels = rng.uniform(-10.0, 10.0, int(np.ceil(span / 0.7)))
    force = levels[(t // 0.7).astype(int)] + 4.0 * np.sin(2 * np.pi * 0.4 * t) + 3.0

    def rate(s, F):
        return np.array([s[1], (F - fc * np.tanh(s[1] / eps) - b * s[1] - load) / m])

    xv = rk4_states(rate, t, force, substeps=10)
    return Experiment(t, {"F": force}, {"x": xv[:, 0] + rng.normal(0, 1e-2, t.size),
                                        "v": xv[:, 1] + rng.normal(0, 2e-3, t.size)},
                      {"F": "N", "x": "m", "v": "m/s"}, "truth")


def test_a_drifting_carriages_friction_and_load_are_told_from_its_drift():
    """The issue's ball-screw shape on the force-driven carriage, whose nominal (no friction, no
    load) drifts by metres, over eight drawn excitations: restarted every 0.6 s (120 samples, the
    segment judge's length), the regression selects the Coulomb + viscous friction and the constant
    load together in five and recovers the load to 5 % there (open-loop: three; on seeds 6-8 the
    drift, the effects' double integral, was explained by a Coulomb or a Stribeck law alone, and on
    the benchmark's carriage by any of a viscous friction, a quadratic drag, a cubic spring and a
    relaxation, 99 % each: ``python -m diagnosis.benchmark.ball_screw``, seed 12, case 005).  Seed 3
    goes the other way (its speeds stay under 0.2 m/s, and within a segment a viscous force hardly
    changes), and where the carriage never reverses (seeds 1 and 4) nothing tells a Coulomb level
    from a load."""
    from diagnosis.graph_location import locate_on_graph
    from plants import library
    graph, place = library.build("carriage"), Place("junction", "v_cart")
    right = {None: [], 120: []}
    for seed in range(1, 9):
        exp = _carriage(seed)
        estimates = {s.place: s.estimate for s in locate_on_graph(graph, exp, places=[place])}
        for restart in right:
            ev = feature_evidence(graph, [place], exp, estimates=estimates, restart=restart)[place]
            if sorted(ev.selected) == ["constant_load", "coulomb_viscous_friction"]:
                right[restart].append(seed)
                load = {k.kind: k.coefficients for k in ev.together}["constant_load"]["1"]
                assert abs(load) == pytest.approx(1.5, rel=0.05)
    assert set(right[120]) >= {5, 6, 7, 8} and len(right[120]) > len(right[None])


def test_the_drifting_carriage_of_the_ball_screw_shape_is_answered_with_both_effects(tmp_path):
    """End to end on the benchmark's carriage (diagnosis.benchmark.ball_screw, seed 12, case 5):
    Coulomb + viscous friction and a constant load, nominal drifting by metres, judged by segments.
    Along the open-loop run the features ranked a quadratic drag, a cubic spring, a relaxation and a
    viscous friction at 99 % each, and the answer was a quadratic drag and a cubic spring (speed's
    held-out segment error 31 % lower); restarted, the regression selects the pair, which recovers
    the load and the friction to 3 % and lowers that error 85 %."""
    from diagnosis.benchmark.ball_screw import cases
    from diagnosis.benchmark.plants import PLANTS
    from diagnosis.benchmark.run import run_case
    first, second = cases(6, 12)[5]
    assert (first.plant, first.kind, second.kind) == ("carriage", "coulomb_viscous_friction", "constant_load")
    r = run_case(first, PLANTS, tmp_path, second=second)
    assert r["judge"] == "segments"
    assert sorted(r["answers"]) == ["constant_load @ junction v_cart", "coulomb_viscous_friction @ junction v_cart"]
    truth = {e["kind"]: e for e in [r["effect"], *r["effect"]["also"]]}
    p, friction = r["parameters"], truth["coulomb_viscous_friction"]
    assert abs(p["F0_v_cart"]) == pytest.approx(truth["constant_load"]["magnitude"], rel=0.03)
    assert p["Fc_v_cart"] == pytest.approx(friction["magnitude"], rel=0.03)
    b = friction["magnitude"] * friction["shape"]["beta"] / friction["shape"]["v_rms"]
    assert p["b_visc_v_cart"] == pytest.approx(b, rel=0.03)
    assert r["improvement"] > 0.8
