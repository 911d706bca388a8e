"""Scenario exo-lqi (seed 004 Section 5.2): relative-angle model, LQI gains vs eqs. (16)-(17),
margins two ways (python-control vs our frequency response), co-simulated loop vs the same
loop as one linear discrete system, JSON shape and plots."""
from __future__ import annotations

import json

import control as ct
import numpy as np
import pytest

from plants.blockdiagram.exoskeleton import state_space
from bondgraph.errors import ParameterError, UnobservableModeError
from reproductions import _exo_analysis as an
from reproductions import _exo_design as de
from reproductions import exo_lqi
from reproductions._exo_loop import monolithic
from estimators.observer import continuous_kalman_gain


@pytest.fixture(scope="module")
def d():
    return de.design(dt=exo_lqi.DT)


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("exo_lqi_plots")
    return exo_lqi.run(out, quick=True), out


def test_relative_model_is_eq_3_in_trunk_relative_angles(d):
    """x_rel = T x_abs (theta_m - r_g theta_h, ..., theta_sext - theta_h): T A = A1 T and
    T B = [Bm, Bh] with A, B of eq. (3) (block diagram, typed from the paper)."""
    A, B, _, _ = state_space(d.params)
    T = np.hstack([np.eye(6), np.zeros((6, 1))])
    T[[0, 2, 4], 6] = [-d.params["r_g"], -1.0, -1.0]
    np.testing.assert_allclose(T @ A, d.A1 @ T, rtol=0, atol=1e-9 * np.abs(A).max())
    np.testing.assert_allclose(T @ B, np.hstack([d.Bm, d.Bh]), rtol=1e-12, atol=0)


def test_absolute_model_is_not_detectable_but_relative_model_is(d):
    """Eq. (5) sensors: the 7-state model's rigid-body mode (eigenvalue 0) is invisible."""
    A, B, C, _ = state_space(d.params)
    with pytest.raises(UnobservableModeError, match="eigenvalue 0"):
        continuous_kalman_gain(A, C[[1, 0]], np.eye(7), np.eye(2))
    assert np.max(d.observer_c.poles.real) < 0 and np.max(np.abs(d.observer_d.poles)) < 1


def test_gains_against_eqs_16_17_and_python_control(d):
    """F_iz = -sqrt(q_w / R) = -sqrt(5e15 / 1e12) = -70.71 as printed in eq. (17) (the
    double-integrator end of the LQ chain); F'_ix entries 4-6 round to the printed 0, 0.02, 0;
    the whole gain equals python-control's lqr on the augmented system of eq. (12)."""
    g = d.lqi2
    assert g.Fiz[0, 0] == pytest.approx(-np.sqrt(5e15 / 1e12), rel=1e-9)
    assert round(float(g.Fiz[0, 0]), 2) == de.PAPER_GAINS["Fiz"]
    assert [round(float(v), 2) for v in g.Fix[0, 3:]] == list(de.PAPER_GAINS["Fix"][3:])
    assert d.lqi1.Fiz_prime[0, 0] == pytest.approx(-np.sqrt(5e13 / 1e12), rel=1e-9)   # eq. (14)
    Ai = np.zeros((8, 8))
    Ai[:6, :6], Ai[6, :6], Ai[7, 6] = d.A1, -d.Cb[0], 1.0            # eq. (12)
    Bi = np.vstack([d.Bm, np.zeros((2, 1))])
    K, _, _ = ct.lqr(Ai, Bi, np.diag(de.Q_C), de.R_C)
    np.testing.assert_allclose(g.K, K, rtol=1e-7)


def test_printed_F_iz_prime_is_the_single_integral_design_with_q_z_1e13(quick_run):
    """Eq. (17)'s F'_iz = -3.16 = -sqrt(1e13 / 1e12): the single-integral design (eqs. (10)-(11))
    with integral weight 1e13; its F'_ix then rounds to the printed 0.03, 0, 0 at entries 2, 4, 6
    and is 0.98 for the printed 1.00 (eq. (16))."""
    g = quick_run[0]["single_integral_qz_1e13"]
    assert round(g["Fiz_prime"], 2) == de.PAPER_GAINS["Fiz_prime"]
    fix = [round(v, 2) for v in g["Fix"]]
    assert [fix[i] for i in (1, 3, 5)] == [de.PAPER_GAINS["Fix"][i] for i in (1, 3, 5)]
    assert abs(g["Fix"][0] - de.PAPER_GAINS["Fix"][0]) < 0.05


def _python_control_loop(d):
    """The loop at the plant input built with python-control only: lqe for the observer gain,
    ss arithmetic for the controller and the series connection."""
    G = np.hstack([d.Bm, d.Bh])
    v = d.noise_var
    L, _, _ = ct.lqe(d.A1, G, d.Cm, np.diag([v["tau_m"], v["w_h"]]), np.diag([v["w_m"], v["tau_s"]]))
    g = d.lqi2
    K = np.hstack([g.Kx, g.Kz, g.Kzz])
    Ac = np.zeros((8, 8))
    Ac[:6, :6] = d.A1 - L @ d.Cm
    Ac[6, :6], Ac[7, 6] = -d.Cb[0], 1.0
    Bu = np.vstack([d.Bm, np.zeros((2, 1))])
    Ac -= Bu @ K
    ctrl = ct.ss(Ac, np.vstack([L, np.zeros((2, 2))]), -K, 0)       # y -> u
    plant = ct.ss(d.A1, d.Bm, d.Cm, 0)
    return -ctrl * plant


def test_margins_two_ways(d):
    """Our crossover search on loop_at_plant_input vs python-control's stability_margins on
    a loop assembled by python-control (lqe + ss series)."""
    ours = an.margins(*de.loop_at_plant_input(d))
    gm, pm, _, wpc, wgc, _ = ct.stability_margins(_python_control_loop(d))
    assert ours.gain == pytest.approx(gm, rel=1e-6)
    assert ours.phase_deg == pytest.approx(pm, rel=1e-6)
    assert ours.w_gc == pytest.approx(wgc, rel=1e-6) and ours.w_pc == pytest.approx(wpc, rel=1e-6)
    assert ours.delay_s == pytest.approx(np.radians(pm) / wgc, rel=1e-6)
    # the LQ loop without observer: python-control on the augmented design
    g = d.lqi2
    lq = an.margins(g.A_aug, g.B_aug, g.K, np.zeros((1, 1)))
    gm2, pm2, *_ = ct.stability_margins(ct.ss(g.A_aug, g.B_aug, g.K, 0))
    assert lq.gain == pytest.approx(gm2, rel=1e-6) and lq.phase_deg == pytest.approx(pm2, rel=1e-6)


def test_gain_margin_is_where_the_closed_loop_loses_stability(d):
    """Third check, by eigenvalues: closing u = -g L with g just below / above the gain margin
    leaves the poles inside / puts one outside (Re 0 for the continuous loop, |z| = 1 sampled)."""
    A, B, C, _ = de.loop_at_plant_input(d)
    gm = an.margins(A, B, C, np.zeros((1, 1))).gain
    assert np.max(np.linalg.eigvals(A - 0.999 * gm * B @ C).real) < 0 < \
        np.max(np.linalg.eigvals(A - 1.001 * gm * B @ C).real)
    A, B, C, _ = de.sampled_loop_at_plant_input(d)
    gm = an.margins(A, B, C, np.zeros((1, 1)), dt=d.dt).gain
    assert np.max(np.abs(np.linalg.eigvals(A - 0.999 * gm * B @ C))) < 1 < \
        np.max(np.abs(np.linalg.eigvals(A - 1.001 * gm * B @ C)))


def test_sampled_loop_margins_against_python_control_frd(d):
    """The discrete loop that runs (0.1 ms): python-control's margins from its own frequency
    response (FRD; its polynomial method is ill-conditioned for this 14th-order loop)."""
    A, B, C, D = de.sampled_loop_at_plant_input(d)
    ours = an.margins(A, B, C, D, dt=d.dt)
    w = np.logspace(0, 4.4, 2000)
    gm, pm, _, wpc, wgc, _ = ct.stability_margins(ct.frd(ct.ss(A, B, C, D, d.dt), w))
    assert ours.gain == pytest.approx(gm, rel=1e-6) and ours.phase_deg == pytest.approx(pm, rel=1e-6)
    assert ours.w_gc == pytest.approx(wgc, rel=1e-6) and ours.w_pc == pytest.approx(wpc, rel=1e-6)
    cont = an.margins(*de.loop_at_plant_input(d))
    assert ours.phase_deg == pytest.approx(cont.phase_deg, abs=0.1)   # 0.1 ms sampling: ~ continuous


def test_bandwidth_against_python_control_response(d):
    """|G| at the reported -3 dB limits is the peak / sqrt(2), evaluated by python-control;
    the DC gain is 0 (double integral action rejects a constant trunk velocity)."""
    A, B, C, D = de.disturbance_to_estimate(d)
    sys = ct.ss(A, B, C[[0]], D[[0]])
    band = an.band_limits(A, B, C[[0]], D[[0]])
    peak = np.max(np.abs(sys(1j * np.logspace(0, 3, 20001))))
    assert band.peak_gain == pytest.approx(peak, rel=1e-6)
    for f in (band.lower_hz, band.upper_hz):
        assert abs(sys(2j * np.pi * f)) == pytest.approx(band.peak_gain / np.sqrt(2), rel=1e-8)
    assert abs(ct.dcgain(sys)) < 1e-9 * band.peak_gain
    assert band.lower_hz < band.peak_hz < band.upper_hz


def test_cosimulated_loop_equals_monolithic_linear_loop():
    """FMU (bond graph, internal RK4) in the master vs eq. (3) discretised exactly with the
    observer and LQI as one discrete linear system (scipy dlsim), same seeded noise."""
    d, res, w = exo_lqi.simulate(quick=True)
    mono = monolithic(d, res.t, w, w_h=exo_lqi.W_H, tau_ref=exo_lqi.TAU_REF, t_ref=exo_lqi.T_REF)
    pairs = {"ctrl.tau_m": "tau_m", "ctrl.y_b_hat": "y_b_hat", "ctrl.w_m_hat": "w_m_hat",
             "plant.tau_b": "y_b", "plant.w_m": "w_m", "plant.tau_s": "tau_s"}
    for ours, ref in pairs.items():
        scale = np.max(np.abs(mono[ref]))
        np.testing.assert_allclose(res[ours], mono[ref], rtol=0, atol=1e-9 * scale, err_msg=ours)
    assert np.max(mono["y_b"]) > 5.0                # the step really happened


def test_noise_free_observer_is_exact_and_noisy_one_beats_the_sensor(d):
    """With the exact ZOH model the noise-free estimate equals the true torque; with the
    Sec. 4 noise the body-torque error stays below the torque sensor's own noise (std 35e-3/sqrt 3)."""
    t = np.arange(2001) * d.dt
    clean = monolithic(d, t, np.zeros((t.size, 4)), w_h=0.1, tau_ref=10.0, t_ref=0.1)
    assert np.max(np.abs(clean["y_b"] - clean["y_b_hat"])) < 1e-9 * np.max(np.abs(clean["y_b"]))
    noisy = monolithic(d, t, exo_lqi.noise(t.size), w_h=0.1, tau_ref=10.0, t_ref=0.1)
    rms = np.sqrt(np.mean((noisy["y_b"] - noisy["y_b_hat"]) ** 2))
    assert rms < 0.1 * de.NOISE_BOUNDS["tau_s"] / np.sqrt(3)


def test_run_json_shape_and_plots(quick_run):
    out, folder = quick_run
    json.dumps(out)
    assert set(out["gains"]) == {"Fix", "Fiz_prime", "Fiz"} and len(out["gains"]["Fix"]) == 6
    assert set(out["margins"]) >= {"gain_db", "phase_deg", "delay_s"}
    for key in ("bandwidth_hz", "max_motor_torque", "estimation_mse"):
        assert isinstance(out[key], float) and np.isfinite(out[key]) and out[key] > 0
    assert out["cosim_vs_monolithic_max_abs"]["tau_m"] < 1e-9
    for name in ("nyquist", "bode", "step", "motor_velocity", "motor_torque"):
        assert (folder / f"exo_lqi_{name}.png").stat().st_size > 10_000


def test_noise_block_names_its_problem():
    from bondgraph.errors import CosimError
    from reproductions._exo_loop import AddNoise
    with pytest.raises(CosimError, match="'act'.*shape \\(n_samples, 2\\)"):
        AddNoise("act", ("tau_m", "w_h"), np.zeros((5, 3)), 1e-4)
    with pytest.raises(CosimError, match="unknown signal.*theta"):
        AddNoise("act", ("theta",), np.zeros((5, 1)), 1e-4)


def test_design_rejects_bad_period():
    with pytest.raises(ParameterError, match="dt"):
        de.design(dt=-1e-3)
    with pytest.raises(ParameterError, match="nope"):
        de.design(params={"nope": 1.0})
