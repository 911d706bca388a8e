"""diagnosis.residuals: simulation on recorded inputs, NRMSE and the noise estimate."""
import numpy as np
import pytest

from plants import library
from bondgraph.numerics import simulate
from bondgraph.errors import ParameterError, UnknownNameError
from diagnosis.errors import DiagnosisError
from diagnosis.recording import Experiment
from diagnosis.residuals import OutputSimulator, noise_sigma, nrmse, residuals, settle_substeps, simulate_outputs


def _msd_step(t, m=1.0, b=0.4, k=4.0):
    """Analytic unit-step response x(t) of m x'' + b x' + k x = 1 (underdamped)."""
    wn = np.sqrt(k / m)
    zeta = b / (2 * np.sqrt(k * m))
    wd = wn * np.sqrt(1 - zeta ** 2)
    return (1 - np.exp(-zeta * wn * t) * (np.cos(wd * t) + zeta * wn / wd * np.sin(wd * t))) / k


def test_step_response_matches_analytic_on_uneven_grid():
    rng = np.random.default_rng(1)
    t = np.sort(np.r_[0.0, rng.uniform(0.0, 5.0, 400), 5.0])
    exp = Experiment(t, {"F": np.ones_like(t)}, {"x": t.copy()}, {"F": "N", "x": "m"})
    x = simulate_outputs(library.build("mass-spring-damper"), exp)["x"]
    np.testing.assert_allclose(x, _msd_step(t), atol=1e-6)   # RK4, h |lambda| <= 0.5


def test_parameters_and_initial_state_are_used():
    t = np.linspace(0.0, 3.0, 301)
    exp = Experiment(t, {"F": np.ones_like(t)}, {"x": t.copy()}, {})
    sim = OutputSimulator(library.build("mass-spring-damper"), exp)
    x = sim(params={"k": 9.0, "b": 1.2})["x"]
    np.testing.assert_allclose(x, _msd_step(t, k=9.0, b=1.2), atol=1e-7)
    # free response from x0 = 0.1 m with F = 1 N: superposition of step and free decay
    x_free = sim(x0={"q_k": 0.1})["x"]
    wn, zeta = 2.0, 0.1
    wd = wn * np.sqrt(1 - zeta ** 2)
    decay = 0.1 * np.exp(-zeta * wn * t) * (np.cos(wd * t) + zeta * wn / wd * np.sin(wd * t))
    np.testing.assert_allclose(x_free, _msd_step(t) + decay, atol=1e-7)
    with pytest.raises(ParameterError, match="unknown parameter 'kk'"):
        sim(params={"kk": 1.0})
    with pytest.raises(UnknownNameError, match="unknown state 'x'"):
        sim(x0={"x": 1.0})


@pytest.fixture(scope="module")
def pam_run():
    t = np.arange(0.0, 1.5 + 1e-9, 1e-3)
    u1, u2 = 5 + 2 * np.sin(2 * np.pi * t), 5 - 2 * np.sin(2 * np.pi * t)
    exp = Experiment(t, {"u1": u1, "u2": u2}, {"psi": t.copy(), "P1": t.copy()}, {})
    return exp, library.build("pam")


def test_pam_equals_bondgraph_simulate(pam_run):
    """Same fixed-step scheme as bondgraph.numerics.simulate (1 ms samples, 4 RK4 sub-steps, ZOH)."""
    exp, graph = pam_run
    ours = OutputSimulator(graph, exp)()
    ref = simulate(graph, exp.span, inputs={k: (exp.t, v) for k, v in exp.inputs.items()},
                   output_interval=1e-3)
    for name in ("psi", "P1"):
        np.testing.assert_allclose(ours[name], ref[name], rtol=1e-12, atol=1e-9)
    assert np.ptp(ours["psi"]) > 1.0   # the joint moves (deg)


def test_batch_and_numpy_backend_agree(pam_run):
    exp, graph = pam_run
    sim = OutputSimulator(graph, exp, outputs=["psi"])
    sets = [None, {"J": 1.3 * graph.equations().param_values["J"]}, {"k_s": 0.5}]
    batch = sim.run_batch(sets)
    for params, run in zip(sets, batch):
        np.testing.assert_allclose(run.outputs["psi"], sim(params)["psi"], rtol=1e-13, atol=1e-12)
    assert np.max(np.abs(batch[1].outputs["psi"] - batch[0].outputs["psi"])) > 1e-3
    short = exp.window(0.0, 0.15)   # the numpy backend is slow: 150 samples
    slow = OutputSimulator(graph, short, outputs=["psi"], backend="numpy")()["psi"]
    np.testing.assert_allclose(slow, batch[0].outputs["psi"][:short.t.size], rtol=1e-9, atol=1e-9)


def test_c_sample_loop_equals_the_python_loop_bit_for_bit(pam_run, monkeypatch):
    """The C driver of evaluate_samples_c makes the same bc_rk4 calls as the Python loop: equal
    states and held values to the last bit, for a batch with different parameters, and also
    when the batch's rows are shared out to three threads (one row each)."""
    from bondgraph.numerics import evaluate_samples
    from bondgraph.numerics.evaluate_samples import rk4_samples
    from bondgraph.numerics.evaluate_samples_c import sample_driver
    exp, graph = pam_run
    sim = OutputSimulator(graph, exp)
    m = sim.model
    if m.backend != "c" or sample_driver() is None:
        pytest.skip("no C compiler")
    J = graph.equations().param_values["J"]
    P = np.vstack([m.param_vector(q) for q in (None, {"J": 1.3 * J}, {"J": 0.8 * J})])
    monkeypatch.setattr(evaluate_samples, "_THREAD_WORK", 0)
    threads_used = []
    real = evaluate_samples._threaded
    monkeypatch.setattr(evaluate_samples, "_threaded",
                        lambda args, chunks, *a: threads_used.append(len(chunks)) or real(args, chunks, *a))
    for every in (1, 2):          # bc_rk4 and bc_rk4_every (8 steps, friction held over 2 of them)
        subs = np.full(exp.t.size - 1, 4 * every)
        out = []
        for use_driver, threads in ((False, "1"), (True, "1"), (True, "3")):
            monkeypatch.setenv("BONDCOSIM_THREADS", threads)
            x, d = np.tile(m.default_state, (3, 1)), np.tile(m.default_held, (3, 1))
            X, D = rk4_samples(m, sim.t, sim.U, subs, x, d, np.ascontiguousarray(P), use_driver=use_driver,
                               every=every)
            out.append((X, D, x, d))
        for ref, other in ((out[0], out[1]), (out[0], out[2])):
            for a, b in zip(ref, other):
                assert np.array_equal(a, b)
        assert np.ptp(out[1][0][:, 0, -1]) > 0.01   # the joint moves
    assert threads_used == [3, 3]


def test_nrmse_definition():
    y = np.array([1.0, 2.0, 3.0, 4.0])
    assert nrmse(y, y) == 0.0
    assert nrmse(y, np.full(4, y.mean())) == pytest.approx(1.0)   # the mean predicts nothing
    # by hand: residual (0.5, -0.5, 0.5, -0.5): rms 0.5; std(y) = sqrt(1.25)
    assert nrmse(y, y + np.array([-0.5, 0.5, -0.5, 0.5])) == pytest.approx(0.5 / np.sqrt(1.25))
    with pytest.raises(DiagnosisError, match="constant"):
        nrmse(np.ones(3), np.zeros(3))
    with pytest.raises(DiagnosisError, match="shape"):
        nrmse(y, y[:3])


def test_noise_sigma_recovers_white_noise_on_a_signal():
    rng = np.random.default_rng(7)
    t = np.arange(0.0, 20.0, 1e-3)
    signal = 3.0 * np.sin(2 * np.pi * 0.5 * t) + (t > 10.0)        # with a step
    for sigma in (0.002, 0.05):
        est = noise_sigma(signal + rng.normal(0.0, sigma, t.size))
        assert est == pytest.approx(sigma, rel=0.05)
    # quantised (step q = 0.01) slow signal without other noise: q / sqrt(12)
    q = 0.01
    est = noise_sigma(np.round(0.3 * t / q) * q)
    assert est == pytest.approx(q / np.sqrt(12), rel=1e-6)


def test_residuals_fields():
    t = np.linspace(0.0, 4.0, 401)
    graph = library.build("mass-spring-damper")
    truth = _msd_step(t)
    exp = Experiment(t, {"F": np.ones_like(t)}, {"x": truth + 0.01}, {"F": "N", "x": "m"})
    res = residuals(graph, exp)
    np.testing.assert_allclose(res.residual["x"], 0.01, atol=1e-7)
    assert res.nrmse["x"] == pytest.approx(0.01 / np.std(truth), rel=1e-4)
    assert res.run.states.shape == (t.size, 2) and res.run.state_names == ("p_m", "q_k")
    with pytest.raises(UnknownNameError, match="unknown output 'y'"):
        residuals(graph, exp, outputs=["y"])


def test_simulator_on_another_experiment_reuses_the_compiled_model():
    """OutputSimulator.on: the same compiled model on another grid gives the analytic step response
    there (m=1, b=0.4, k=4), and the outputs of a freshly compiled simulator."""
    t1, t2 = np.linspace(0.0, 1.0, 101), np.linspace(0.0, 3.0, 601)
    exp1 = Experiment(t1, {"F": np.ones_like(t1)}, {"x": t1}, {"F": "N", "x": "m"})
    exp2 = Experiment(t2, {"F": np.ones_like(t2)}, {"x": t2}, {"F": "N", "x": "m"})
    sim = OutputSimulator(library.build("mass-spring-damper"), exp1)
    other = sim.on(exp2)
    assert other.model is sim.model
    y = other({"k": 4.0})["x"]
    np.testing.assert_allclose(y, _msd_step(t2), atol=1e-6)
    np.testing.assert_array_equal(y, OutputSimulator(library.build("mass-spring-damper"), exp2)()["x"])
    assert sim()["x"].shape == t1.shape          # the original keeps its own grid


def _coarse_step(sigma, dt=0.25, T=60.0):
    """The msd's step response sampled at 4 Hz (h |lambda| = 0.5: one RK4 sub-step by the step
    rule), with the truth analytic."""
    t = np.arange(0.0, T + dt / 2, dt)
    exp = Experiment(t, {"F": np.ones_like(t)}, {"x": _msd_step(t)}, {"F": "N", "x": "m"})
    return OutputSimulator(library.build("mass-spring-damper"), exp), {"x": sigma}


def test_the_step_is_halved_until_the_integration_error_is_well_under_the_noise():
    sigma = 2e-5                                             # m: a fine position sensor
    sim, noise = _coarse_step(sigma)
    t = sim.experiment.t
    coarse = sim()["x"]
    assert sim.run().substeps == 1
    assert np.sqrt(np.mean((coarse - _msd_step(t)) ** 2)) > 3 * sigma     # the step rule's error
    exp, rule = settle_substeps(sim, None, noise)
    assert rule == 1 and exp.substeps > 1
    settled = sim.on(exp)()["x"]
    assert np.sqrt(np.mean((settled - _msd_step(t)) ** 2)) < 0.2 * sigma
    # the parts of the experiment keep it, and so does every simulator on them
    train, held = exp.split(0.3)
    assert train.substeps == held.substeps == exp.substeps == sim.on(held).run().substeps


def test_a_noisy_recording_keeps_the_step_rule():
    sim, noise = _coarse_step(sigma=0.01)                    # the step rule's error is under 0.1 sigma
    exp, rule = settle_substeps(sim, None, noise)
    assert exp is sim.experiment and exp.substeps == 1 and rule == 1


def test_a_stiff_law_on_a_held_variable_model_nests_finer_steps_in_the_held_laws_interval():
    """The pam joint with a Coulomb friction at the seesaw sharp at 0.1 mrad/s (|lambda| h about
    6 at its 0.25 ms steps, past RK4's stability): the diagnosis's simulator nests finer RK4 steps
    in each 0.25 ms interval of the Kikuuwe friction (Z = h / J stays the plant's) and follows the
    benchmark's hand-written truth with the same friction (seed 3535, case 019: before, the
    catalogue's Stribeck law at the truth's own values was 32 noise sigmas of tau off it)."""
    from diagnosis.benchmark.effects import make_effect
    from diagnosis.benchmark.plants import PLANTS
    from diagnosis.benchmark.simulate import simulate_truth
    from diagnosis.catalogue import candidates
    from diagnosis.place import Place

    plant = PLANTS["pam"]()
    t = np.arange(0.0, 0.6, 1.0 / plant.rate)
    u = {"u1": np.where(t < 0.3, 8.0, 2.0), "u2": np.where(t < 0.3, 2.0, 8.5)}
    level, eps = 0.01, 1e-4
    truth = simulate_truth(plant, t, u, make_effect("coulomb_friction", plant, "junction", "seesaw", level, {},
                                                    {"eps": eps, "sign": 1.0}))
    graph = library.build(plant.model)
    exp = Experiment(t, u, {o.name: truth[o.name] for o in plant.outputs},
                     {"u1": "V", "u2": "V", **{o.name: o.unit for o in plant.outputs}})
    cand = next(c for c in candidates(graph, Place("junction", "seesaw")) if c.kind == "coulomb_friction")
    fc, v_eps = (p.name for p in cand.params)
    sim = OutputSimulator(cand.build(graph, {fc: level, v_eps: eps}), exp)
    run = sim.run(None, plant.nominal_x0)
    assert run.substeps > 4                 # RK4 steps per 1 ms sample: finer than the law's 0.25 ms
    y = run.outputs
    for o in ("psi", "tau"):
        spread = float(np.ptp(truth[o]))
        assert np.max(np.abs(y[o] - truth[o])) < 0.02 * spread, o
    # the numpy backend's bc_rk4_every (its reference) gives the same numbers on the first 10 ms
    short = exp.window(0.0, 0.01)
    slow = OutputSimulator(cand.build(graph, {fc: level, v_eps: eps}), short, backend="numpy")(x0=plant.nominal_x0)
    np.testing.assert_allclose(slow["psi"], y["psi"][:short.t.size], rtol=1e-9, atol=1e-9)


def test_a_run_takes_the_integrator_it_takes_alone_whatever_it_is_batched_with():
    """A smoothed Coulomb friction so sharp that its slope at rest needs more than 1000 RK4
    sub-steps per sample runs on the Rosenbrock path; a blunt one runs on RK4.  Batched together,
    each gives the outputs it gives alone (before, the sharp run put the whole batch on ROS2 at the sub-steps of
    both: the blunt run's speed moved by 0.2 % of its spread, the sharp run's by 25 %)."""
    from test_diagnosis_fit import F, T, UNITS, coulomb_truth
    sim = OutputSimulator(coulomb_truth(), Experiment(T, {"F": F}, {"x": T, "v": T}, UNITS))
    blunt, sharp = {"Fc_true": 0.3, "v_true": 0.02}, {"Fc_true": 3.0, "v_true": 1e-7}
    alone = [sim.run(p) for p in (blunt, sharp)]
    together = sim.run_batch([blunt, sharp, blunt])
    for run, ref in zip(together, alone + alone[:1]):
        for o in ("x", "v"):
            assert np.max(np.abs(run.outputs[o] - ref.outputs[o])) <= 1e-9 * np.ptp(ref.outputs[o])


def test_a_batchs_rk4_runs_take_their_own_sub_steps_unless_they_are_alike():
    """A blunt Coulomb friction needs 1 RK4 sub-step per sample, a sharp one 93 (both below the
    Rosenbrock path's).  Batched, each runs at its own and gives its outputs alone to the last
    bit; before, the blunt run took the sharp one's 93 (on the pam a fit's sharp start imposed
    744 sub-steps on three others that need 4-152: seed 4848, case 034).  Runs whose sub-steps are
    within a factor 4 (a finite-difference Jacobian's) still share the shortest one."""
    from test_diagnosis_fit import F, T, UNITS, coulomb_truth

    from diagnosis.residuals import _alike_steps
    sim = OutputSimulator(coulomb_truth(), Experiment(T, {"F": F}, {"x": T, "v": T}, UNITS))
    blunt, sharp = {"Fc_true": 0.3, "v_true": 0.02}, {"Fc_true": 3.0, "v_true": 1e-4}
    alone = [sim.run(p) for p in (blunt, sharp)]
    together = sim.run_batch([blunt, sharp, blunt])
    assert [r.substeps for r in alone] == [1, 93] and [r.substeps for r in together] == [1, 93, 1]
    for run, ref in zip(together, alone + alone[:1]):
        for o in ("x", "v"):
            np.testing.assert_array_equal(run.outputs[o], ref.outputs[o])
    groups = _alike_steps(np.arange(5), np.array([1e-3, 1e-5, 0.9e-3, 3e-4, 2e-3]))
    assert [list(g) for g in groups] == [[0, 2, 4], [3], [1]]


def test_the_stiff_path_takes_over_sooner_the_more_a_derivative_costs():
    """A run goes to the Rosenbrock path where it would cost more on RK4 (residuals._stiff_from,
    a cost model in the operations of the state derivatives): the mass-spring-damper keeps RK4 up
    to 1000 sub-steps per sample, as the exoskeleton does (RK4 at 515 sub-steps was 2-3 times
    cheaper there), while the same plant with a seal law of 300 terms switches at 300 or fewer
    (the pam-frictionless, 1512 operations, at 154)."""
    from bondgraph import R
    from plants.library import mass_spring_damper
    t = np.linspace(0.0, 1.0, 11)
    exp = Experiment(t, {"F": np.zeros_like(t)}, {"x": t}, {"F": "N", "x": "m"})
    cheap = OutputSimulator(library.build("mass-spring-damper"), exp)
    heavy_graph = mass_spring_damper(b=0.4)
    heavy_graph.add(R("seal", effort="c*(" + " + ".join(f"tanh(f/{k + 1})" for k in range(300)) + ")",
                      params={"c": 1e-3}, domain="translation"))
    heavy_graph.connect("v_mass", "seal")
    heavy = OutputSimulator(heavy_graph, exp)
    assert cheap._stiff_from() == 1000
    assert heavy._stiff_from() <= 300
    assert heavy._stiff(np.array([500])) and not cheap._stiff(np.array([500]))
    assert heavy.on(exp)._stiff_limit == heavy._stiff_from()       # counted once per model


def test_a_law_stiff_only_in_motion_gets_the_sub_step_its_run_needs():
    """A Dahl friction (0.1 N, 1000 N/m) on the msd relaxes at sigma |v| / F_h, 0 at rest: the
    sub-step from the start state (2 per 20 ms sample) went to infinity once the mass moved (a
    carriage's Dahl fit diverged so, seed 3434, compound case 007).  The states of that run, up to
    where it went past RK4's stability, now set it: finite, and equal to a run at 800 sub-steps
    per sample."""
    from dataclasses import replace
    from test_diagnosis_fit import F, T, UNITS, _candidate
    from diagnosis.place import Place
    msd = library.build("mass-spring-damper")
    exp = Experiment(T, {"F": F}, {"x": T, "v": T}, UNITS)
    cand = _candidate(msd, Place("junction", "v_mass"), "hysteresis", exp)
    level, sigma = (p.name for p in cand.params)
    graph = cand.build(msd, {level: 0.1, sigma: 1e3})
    sim = OutputSimulator(graph, exp)
    assert sim._substeps(sim._sub_step(sim.initial_state(None), sim.model.param_vector(None)))[0].max() <= 2
    run = sim.run()
    assert run.substeps > 20
    fine = OutputSimulator(graph, replace(exp, substeps=800))()
    for o in ("x", "v"):
        assert np.isfinite(run.outputs[o]).all()
        assert np.max(np.abs(run.outputs[o] - fine[o])) < 1e-4 * np.ptp(fine[o])
