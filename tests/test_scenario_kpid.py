"""Scenario kpid (seed 002, Section 3): the plant of eq. (15), its FMU, the loop, the indicators."""
import json

import numpy as np
import pytest
import scipy.linalg
import scipy.signal

from reproductions import _kpid_metrics as metrics
from reproductions import kpid
from reproductions._kpid_plant import arx_response, continuous_modes, pam_single_equations
from estimators.kpid import PAPER_SIMULATION, kpid_model, kpid_model_zoh

# eq. (15) of seed 002 as a transfer function in z: numerator, denominator
NUM15 = [0.0, 0.0111, 0.0102, 0.0093]
DEN15 = [1.0, -0.3914, -0.333, -0.2745]


@pytest.fixture(scope="module")
def plant_fmu(tmp_path_factory):
    return kpid.export_plant(tmp_path_factory.mktemp("kpid") / "pam_single.fmu")


def test_plant_equations_zoh_is_eq_15_python_control():
    """The state equations' ZOH at 1 ms (python-control c2d) is eq. (15), coefficient by coefficient."""
    import control
    lin = pam_single_equations().linearize()
    sysd = control.c2d(control.ss(lin.A, lin.B, lin.C, lin.D), 1e-3, method="zoh")
    tf = control.ss2tf(sysd)
    num, den = np.ravel(tf.num[0][0]), np.ravel(tf.den[0][0])
    num = np.concatenate([np.zeros(4 - num.size), num]) / den[0]
    np.testing.assert_allclose(den / den[0], DEN15, atol=1e-12)
    np.testing.assert_allclose(num, NUM15, atol=1e-12)
    assert control.dcgain(control.ss(lin.A, lin.B, lin.C, lin.D)) == pytest.approx(0.0306 / 0.0011, rel=1e-9)


def test_continuous_modes_from_residues_match_the_matrix_logarithm():
    """Residue mapping of the module docstring vs scipy.linalg.logm of a realisation of (15)."""
    A, B, C, _ = scipy.signal.tf2ss(NUM15, DEN15)
    M = scipy.linalg.logm(np.block([[A, B], [np.zeros((1, 4))]]) + np.diag([0, 0, 0, 1.0])) / 1e-3
    Ac = M.real[:3, :3]
    m = continuous_modes()
    expected = np.sort_complex(np.linalg.eigvals(Ac))
    s = np.sort_complex(np.roots([1.0, m["p_s"]]).tolist()
                        + np.roots([1.0, 2 * m["sigma"], m["omega2"]]).tolist())
    np.testing.assert_allclose(s, expected, rtol=1e-9)
    assert m["c0"] < 0.0        # the fast mode's negative static gain: no passive bond graph


def test_fmu_open_loop_equals_eq_15(plant_fmu):
    from cosim import CoSimulation, FMUComponent, Table
    rng = np.random.default_rng(3)
    n, T = 400, 1e-3
    u = rng.normal(1.0, 2.0, n + 1)
    sim = CoSimulation([Table("u", np.arange(n + 1) * T, u, interpolation="hold"),
                        FMUComponent(plant_fmu, "plant")], [("u.y", "plant.u")], step=T)
    res = sim.run(n * T)
    np.testing.assert_allclose(res["plant.y_mm"], arx_response(u), rtol=0, atol=1e-10)


@pytest.mark.parametrize("kind", ("pid", "kpid"))
def test_fmu_closed_loop_equals_monolithic_loop(plant_fmu, kind):
    """Master + FMU + blocks vs eq. (15) written as one Python loop, same noise sequence."""
    n = 1500
    r, m = kpid.noise(n + 1)
    res = kpid.cosimulate(plant_fmu, kpid.make_controller(kind), kpid.reference("periodic"), r, m, n * 1e-3)
    yd = kpid.reference("periodic")(res.t)
    mono = kpid.monolithic(kpid.make_controller(kind), yd, r, m)
    assert np.ptp(mono["y"]) > 20.0
    for sig, key in (("plant.y_mm", "y"), ("meas.y", "y_v"), ("ctrl.y_e", "y_e")):
        np.testing.assert_allclose(res[sig], mono[key], rtol=0, atol=1e-8, err_msg=sig)
    np.testing.assert_allclose(res["ctrl.u"], mono["u"], rtol=0, atol=1e-6)   # u = 26 e: amplified


def test_kpid_filter_model_zoh_against_scipy():
    """The KPID filter's model (5) at the paper's gains: ZOH vs scipy.signal.cont2discrete."""
    p = PAPER_SIMULATION
    A, B, C = kpid_model(p["Kp"], p["Ki"], p["Kd"])
    ref = scipy.signal.cont2discrete((A, B, C, np.zeros((1, 1))), p["T"], method="zoh")
    Ad, Bd, _ = kpid_model_zoh(p["Kp"], p["Ki"], p["Kd"], p["T"])
    np.testing.assert_allclose(Ad, ref[0], rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(Bd, ref[1], rtol=1e-9, atol=1e-15)
    # the printed eq. (7) (e^{+T Kp / 2 Kd}) is expm(-A T): its A11 is about 7.2e10, not ~0
    assert scipy.linalg.expm(-A * p["T"])[0, 0] == pytest.approx(np.exp(25.0), rel=1e-6)
    assert abs(Ad[0, 0]) < 1e-10


def test_step_metrics_on_hand_made_responses():
    t = np.arange(0, 1.001, 0.01)
    # first order y = 30 (1 - exp(-t / 0.1)): 10-90 % rise time tau ln 9, no overshoot,
    # 2 % settling tau ln 50 (sampled: first sample after), steady-state error 30 exp(-t/tau) mean
    y = 30.0 * (1.0 - np.exp(-t / 0.1))
    m = metrics.step_metrics(t, y, 30.0)
    assert m["rise_time_s"] == pytest.approx(0.1 * np.log(9.0), abs=0.011)
    assert m["overshoot_pct"] == 0.0
    assert m["settling_time_s"] == pytest.approx(0.1 * np.log(50.0), abs=0.011)
    tail = t >= t[int(np.floor(0.75 * t.size))]
    assert m["steady_state_error_mm"] == pytest.approx(np.mean(30.0 * np.exp(-t[tail] / 0.1)), rel=1e-12)
    # hand-made samples: 0, 10, 28, 33, 30.3, 30 ...: rise 10 % (3 mm) at 0.01, 90 % (27) at 0.02
    y = np.array([0.0, 10.0, 28.0, 33.0, 30.3, 30.0, 30.0, 30.0])
    m = metrics.step_metrics(np.arange(8) * 0.01, y, 30.0)
    assert m["rise_time_s"] == pytest.approx(0.01)
    assert m["overshoot_pct"] == pytest.approx(10.0)
    assert m["settling_time_s"] == pytest.approx(0.04)     # |y - 30| <= 0.6 from 0.04 s on
    assert m["steady_state_bias_mm"] == 0.0
    # never settles: last sample outside the band
    assert metrics.step_metrics(np.arange(4.0), [0.0, 30.0, 30.0, 35.0], 30.0)["settling_time_s"] is None
    assert metrics.step_metrics(np.arange(3.0), [0.0, 1.0, 2.0], 30.0)["rise_time_s"] is None


def test_tracking_precision_by_hand():
    yd = np.array([0.0, 20.0, 40.0, 20.0])
    y = np.array([1.0, 18.0, 40.0, 21.0])
    assert metrics.tracking_precision_pct(yd, y) == pytest.approx(100 * (1 + 2 + 0 + 1) / 4 / 40)
    with pytest.raises(ValueError, match="non-constant reference"):
        metrics.tracking_precision_pct([30.0, 30.0], [1.0, 2.0])


def test_run_quick_json_and_plots(tmp_path):
    res = kpid.run(tmp_path, quick=True)
    json.dumps(res)
    keys = {"tracking_precision_pct", "rise_time_s", "overshoot_pct", "settling_time_s",
            "steady_state_error_mm"}
    assert set(res["pid"]) == keys and set(res["kpid"]) == keys and isinstance(res["reading"], str)
    assert isinstance(res["kpid_beats_pid"], bool) and res["verdict"].startswith("on the true plant output")
    # noise-free P-dominated PID: static error y_d / (1 + Kp G(1)) (G(1) = 0.0306 / 0.0011)
    assert res["noise_free"]["pid"]["steady_state_error_mm"] == pytest.approx(
        30.0 / (1.0 + 25.0 * 0.0306 / 0.0011), rel=2e-3)
    # the filter barely uses the measurement: M C = P C'/(C P C' + R) with C P C' ~ Q / Kp^2
    assert res["kalman_gain_MC"] == pytest.approx((1 / 625) / (1 + 1 / 625), rel=2e-3)
    assert sorted(p.name for p in tmp_path.glob("*.png")) == [
        "kpid_periodic_gaussian.png", "kpid_periodic_noise_free.png",
        "kpid_step_gaussian.png", "kpid_step_noise_free.png"]
