"""LQR/LQI, PID/KPID and the PAM PI against independent references.

References: python-control 0.10 ``lqr``/``dlqr`` (including its own
``integral_action`` augmentation), scipy ``cont2discrete``, closed-form
solutions written out here (ZOH of seed 002's model (5), the first samples of
eq. (14) and of seed 000's PI), and a structural fact of the LQR: a state
whose column of A is zero (a pure integrator end) gets |K_i| = sqrt(Q_ii / R)
for a single input (the (i, i) entry of the Riccati equation), which fixes
F_iz of seed 004, eq. (17) from the weights of eq. (15) alone.
"""
import numpy as np
import pytest
import scipy.signal

from bondgraph.errors import EstimatorError, UncontrollableModeError
from estimators import (KPID, PID, DiscretePI, LQIController, augment_integral, dlqi, dlqr, kpid_model_zoh, lqi,
                        lqr)
from estimators.kpid import PAPER_SIMULATION

control = pytest.importorskip("control")


def _plant(rng, n=4, m=2):
    return rng.normal(size=(n, n)), rng.normal(size=(n, m))


def _spd(rng, n, floor=0.1):
    M = rng.normal(size=(n, n))
    return M @ M.T + floor * np.eye(n)


# -- LQR -----------------------------------------------------------------------------------
def test_lqr_and_dlqr_match_python_control():
    rng = np.random.default_rng(1)
    A, B = _plant(rng)
    Q, R = _spd(rng, 4), _spd(rng, 2)
    N = 0.05 * rng.normal(size=(4, 2))
    for ours, ref in ((lqr(A, B, Q, R), control.lqr(A, B, Q, R)),
                      (lqr(A, B, Q, R, N=N), control.lqr(A, B, Q, R, N))):
        np.testing.assert_allclose(ours.K, ref[0], rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(ours.S, ref[1], rtol=1e-9, atol=1e-12)
        assert np.max(ours.poles.real) < 0
    F = A * 1.2 / np.max(np.abs(np.linalg.eigvals(A)))       # open-loop unstable
    ours, ref = dlqr(F, B, Q, R, N=N), control.dlqr(F, B, Q, R, N)
    np.testing.assert_allclose(ours.K, ref[0], rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(ours.S, ref[1], rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(np.sort_complex(ours.poles), np.sort_complex(ref[2]), rtol=1e-9, atol=1e-12)
    assert np.max(np.abs(ours.poles)) < 1


# -- LQI -----------------------------------------------------------------------------------
def test_single_integral_lqi_matches_python_control_integral_action():
    """python-control integrates +C x (no reference); ours r - Cz x: same gains with its C = -Cz."""
    rng = np.random.default_rng(2)
    A, B = _plant(rng)
    Cz = rng.normal(size=(1, 4))
    Q, R = _spd(rng, 5), _spd(rng, 2)
    ours = lqi(A, B, Cz, Q, R)
    K, S, E = control.lqr(A, B, Q, R, integral_action=-Cz)
    np.testing.assert_allclose(ours.K, K, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(np.hstack([ours.Kx, ours.Kz]), K, rtol=1e-9, atol=1e-12)
    assert ours.Kzz is None and np.max(ours.poles.real) < 0
    dt = 0.05
    F = A * 0.95 / np.max(np.abs(np.linalg.eigvals(A)))
    ours = dlqi(F, B, Cz, Q, R, dt=dt)
    K, S, E = control.dlqr(F, B, Q, R, integral_action=-dt * Cz)   # z[k+1] = z[k] - dt Cz x[k]
    np.testing.assert_allclose(ours.K, K, rtol=1e-9, atol=1e-12)
    assert np.max(np.abs(ours.poles)) < 1


def test_double_integral_lqi_matches_python_control_on_the_augmented_system():
    rng = np.random.default_rng(3)
    A, B = _plant(rng, n=3, m=1)
    Cz, Dz = rng.normal(size=(1, 3)), np.array([[0.3]])
    Q, R = _spd(rng, 5), np.array([[0.7]])
    # augmentation written out independently: z' = r - Cz x - Dz u, w' = z
    Aa = np.block([[A, np.zeros((3, 2))], [-Cz, np.zeros((1, 2))], [np.zeros((1, 3)), np.ones((1, 1)),
                                                                      np.zeros((1, 1))]])
    Ba = np.vstack([B, -Dz, [[0.0]]])
    np.testing.assert_array_equal(augment_integral(A, B, Cz, order=2, Dz=Dz)[0], Aa)
    ours = lqi(A, B, Cz, Q, R, order=2, Dz=Dz)
    K, S, E = control.lqr(Aa, Ba, Q, R)
    np.testing.assert_allclose(ours.K, K, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(np.hstack([ours.Kx, ours.Kz, ours.Kzz]), K, rtol=1e-9, atol=1e-12)
    assert np.max(ours.poles.real) < 0
    # discrete: F_aug = [[F, 0, 0], [-dt Cz, 1, 0], [0, dt, 1]]
    dt = 0.02
    F, G = scipy.signal.cont2discrete((A, B, Cz, Dz), dt, method="zoh")[:2]
    Fa = np.block([[F, np.zeros((3, 2))], [-dt * Cz, np.array([[1.0, 0.0]])], [np.zeros((1, 3)),
                                                                                np.array([[dt, 1.0]])]])
    Ga = np.vstack([G, -dt * Dz, [[0.0]]])
    ours = dlqi(F, G, Cz, Q, R, dt=dt, order=2, Dz=Dz)
    K, S, E = control.dlqr(Fa, Ga, Q, R)
    np.testing.assert_allclose(ours.K, K, rtol=1e-9, atol=1e-12)
    assert np.max(np.abs(ours.poles)) < 1


def _exo_design(order):
    from plants.blockdiagram.exoskeleton import state_space
    from plants.library.exoskeleton import parameter_values

    A, B, C, _ = state_space(parameter_values({"b_f": 0.0}))
    A1, Bm, Cb = A[:6, :6], B[:6, [0]], C[[2], :6]            # eqs. (4), (7)
    q = [1e5, 1e5, 1e7, 1e7, 1e7, 1e7, 5e13] + ([5e15] if order == 2 else [])
    return lqi(A1, Bm, Cb, np.diag(q), [[1e12]], order=order)   # eqs. (14)-(15)


def test_exoskeleton_lqi_integral_gains_follow_from_the_weights():
    """Seed 004: with eq. (15), F_iz = -sqrt(5e15 / 1e12) = -70.71 as printed in eq. (17),
    whatever the (partly assumed) drive parameters; with eq. (14) the single-integral
    F'_iz = -sqrt(5e13 / 1e12) = -7.07 (eq. (17) prints -3.16 for F'_iz)."""
    double = _exo_design(2)
    assert double.Fiz[0, 0] == pytest.approx(-np.sqrt(5e3), rel=1e-9)
    assert round(double.Fiz[0, 0], 2) == -70.71
    assert np.max(double.poles.real) < 0
    single = _exo_design(1)
    assert single.Fiz_prime[0, 0] == pytest.approx(-np.sqrt(50.0), rel=1e-9)
    assert single.Fiz is None and np.max(single.poles.real) < 0
    assert double.Fix.shape == (1, 6) and double.Fix[0, 0] > 0      # signs as eq. (16)


def _ramp_run(order, n_steps=4000, dt=0.01):
    # mass-spring-damper (m = 1 kg, k = 4 N/m, c = 0.8 N s/m), force input, position output
    A, B, Cz = np.array([[0.0, 1.0], [-4.0, -0.8]]), np.array([[0.0], [1.0]]), np.array([[1.0, 0.0]])
    F, G = scipy.signal.cont2discrete((A, B, Cz, [[0.0]]), dt, method="zoh")[:2]
    q = [10.0, 1.0, 100.0] + ([100.0] if order == 2 else [])
    ctrl = LQIController(dlqi(F, G, Cz, np.diag(q), [[0.1]], dt=dt, order=order))
    x, err = np.zeros(2), np.empty(n_steps)
    for k in range(n_steps):
        r = 0.5 * k * dt                                         # ramp, 0.5 m/s
        err[k] = r - Cz[0] @ x
        x = F @ x + G @ ctrl.step([r], x)
    return err


def test_double_integral_lqi_tracks_a_ramp_without_steady_state_error():
    err2 = _ramp_run(2)
    assert np.max(np.abs(err2[-500:])) < 1e-9
    err1 = _ramp_run(1)                                          # single action: constant lag
    assert np.ptp(err1[-500:]) < 1e-9 and abs(err1[-1]) > 1e-3


def test_lqi_controller_integrates_as_the_augmented_model():
    rng = np.random.default_rng(4)
    F, G = 0.5 * rng.normal(size=(3, 3)), rng.normal(size=(3, 1))
    Cz = rng.normal(size=(1, 3))
    gain = dlqi(F, G, Cz, np.eye(5), [[1.0]], dt=0.1, order=2)
    ctrl, xa = LQIController(gain), np.zeros(5)
    for k in range(20):
        x, r = rng.normal(size=3), np.array([np.sin(k)])
        u = ctrl.step(r, x)
        xa[:3] = x
        np.testing.assert_allclose(u, -gain.K @ xa, rtol=1e-12, atol=1e-14)
        xa = gain.A_aug @ xa + gain.B_aug @ u + gain.E_aug @ r    # integrator rows only matter
        np.testing.assert_allclose(np.r_[ctrl.z, ctrl.w], xa[3:], rtol=1e-12, atol=1e-14)


def test_lqr_bad_input_is_named():
    with pytest.raises(EstimatorError, match="R must be symmetric positive definite") as info:
        lqr(np.eye(2), np.eye(2), np.eye(2), np.diag([1.0, 0.0]))
    assert info.value.name == "R"
    with pytest.raises(EstimatorError, match=r"B: expected shape \(2, any\) but found \(3, 1\)"):
        lqr(np.eye(2), np.ones((3, 1)), np.eye(2), [[1.0]])
    with pytest.raises(UncontrollableModeError, match=r"eigenvalue 1 .*x1") as info:
        lqr(np.diag([-1.0, 1.0]), [[1.0], [0.0]], np.eye(2), [[1.0]])
    assert info.value.eigenvalue == 1
    # y = s/(s+1) u has a zero at s = 0: its integral cannot be driven
    with pytest.raises(UncontrollableModeError, match="int_e0"):
        lqi([[-1.0]], [[1.0]], [[-1.0]], np.eye(2), [[1.0]], Dz=[[1.0]])
    with pytest.raises(EstimatorError, match="needs dt"):
        LQIController(lqi([[-1.0]], [[1.0]], [[1.0]], np.eye(2), [[1.0]]))
    with pytest.raises(EstimatorError, match="order must be 1"):
        lqi([[-1.0]], [[1.0]], [[1.0]], np.eye(2), [[1.0]], order=3)


# -- PID / KPID (seed 002) ---------------------------------------------------------------------
def test_pid_first_samples_by_hand():
    pid = PID(2.0, 10.0, 0.01, T=0.01)
    # e = 1, 0.5, 0.2; u = Kp e + Ki T sum(e) + Kd (e - e_prev) / T, e_prev(0) = 0
    expected = [2.0 + 0.1 * 1.0 + 1.0, 1.0 + 0.1 * 1.5 - 0.5, 0.4 + 0.1 * 1.7 - 0.3]
    for _ in range(2):                                          # and again after reset
        got = [pid.step(1.0, y) for y in (0.0, 0.5, 0.8)]
        np.testing.assert_allclose(got, expected, rtol=1e-14)
        pid.reset()


def _closed_form_zoh(Kp, Ki, Kd, T):
    """ZOH of model (5) by Sylvester's formula with the real eigenvalues l1, l2 (over-damped)."""
    a, q = Kp / (2 * Kd), Ki / Kd
    l2 = -a - np.sqrt(a * a - q)
    l1 = q / l2                                                 # l1 l2 = q, without cancellation
    e1, e2, d = np.exp(l1 * T), np.exp(l2 * T), l1 - l2
    Ad = np.array([[(l1 * e1 - l2 * e2) / d, -q * (e1 - e2) / d],
                   [(e1 - e2) / d, (l1 * e2 - l2 * e1) / d]])
    Bd = np.array([[(e1 - e2) / d], [(np.expm1(l1 * T) / l1 - np.expm1(l2 * T) / l2) / d]])
    return Ad, Bd


def test_kpid_model_is_the_exact_zoh():
    p = PAPER_SIMULATION
    Ad, Bd, C = kpid_model_zoh(p["Kp"], p["Ki"], p["Kd"], p["T"])
    Ad_ref, Bd_ref = _closed_form_zoh(p["Kp"], p["Ki"], p["Kd"], p["T"])
    np.testing.assert_allclose(Ad, Ad_ref, rtol=1e-9, atol=1e-300)
    np.testing.assert_allclose(Bd, Bd_ref, rtol=1e-9, atol=1e-300)
    np.testing.assert_array_equal(C, [[-1.0 / p["Kd"], 0.0]])
    # a milder set, against scipy
    A = np.array([[-2.0 / 0.5, -3.0 / 0.5], [1.0, 0.0]])
    ref = scipy.signal.cont2discrete((A, np.array([[1.0], [0.0]]), C, np.zeros((1, 1))), 0.01, method="zoh")
    Ad, Bd, _ = kpid_model_zoh(2.0, 3.0, 0.5, 0.01)
    np.testing.assert_allclose(Ad, ref[0], rtol=1e-12)
    np.testing.assert_allclose(Bd, ref[1], rtol=1e-12)


def test_kpid_first_samples_by_hand():
    """Eqs. (8)-(14) of seed 002 written out with the closed-form model and the short
    covariance update (10); P(0) = 0, x(0) = 0, u(-1) = 0."""
    p = PAPER_SIMULATION
    Kp, Ki, Kd, T, Qn, Rn = p["Kp"], p["Ki"], p["Kd"], p["T"], p["Q"], p["R"]
    A, B = _closed_form_zoh(Kp, Ki, Kd, T)
    C = np.array([[-1.0 / Kd, 0.0]])
    kpid = KPID(Kp, Ki, Kd, T=T, Q=Qn, R=Rn)
    yd, ys = 30.0, (3.0, -4.0, 12.0)
    x, P, u, e_sum, e_prev = np.zeros((2, 1)), np.zeros((2, 2)), 0.0, 0.0, 0.0
    for yv in ys:
        x = A @ x + B * u                                       # (11)
        P = A @ P @ A.T + Qn * B @ B.T                          # (8)
        M = P @ C.T / (C @ P @ C.T + Rn)                        # (9)
        x = x + M * (yv - C @ x - yd)                           # (12), consistent form
        P = (np.eye(2) - M @ C) @ P                             # (10)
        e2 = yd - ((C @ x)[0, 0] + yd)                          # (13), e2 = yd - ye
        e_sum += e2
        u = Kp * e2 + Ki * T * e_sum + Kd * (e2 - e_prev) / T   # (14)
        e_prev = e2
        assert kpid.step(yd, yv) == pytest.approx(u, rel=1e-9)
        assert kpid.filtered == pytest.approx(yd - e2, rel=1e-12)
    kpid.reset()
    assert kpid.step(yd, ys[0]) == pytest.approx(kpid.__class__(Kp, Ki, Kd, T=T, Q=Qn, R=Rn).step(yd, ys[0]))


def test_pid_and_kpid_bad_input():
    with pytest.raises(EstimatorError, match="T must be finite and > 0") as info:
        PID(1.0, 1.0, 1.0, T=0.0)
    assert info.value.name == "T"
    with pytest.raises(EstimatorError, match="Kd must be finite and non-zero"):
        KPID(1.0, 1.0, 0.0, T=1e-3, Q=1.0, R=1.0)
    with pytest.raises(EstimatorError, match="R must be finite and > 0"):
        KPID(1.0, 1.0, 1.0, T=1e-3, Q=1.0, R=0.0)


# -- PI of seed 000 ---------------------------------------------------------------------------
def test_pam_pi_first_samples_by_hand():
    pi = DiscretePI.from_paper("angle")                       # TP = 5.45, TI = 1.55, Tstp = 1 ms
    c = 1.55 * 1e-3
    # e = 0.2, 0.15, 0.1; x before each sample = 0, 0.2, 0.35; u1 = 5.5 + c x + TP e, u2 = 11 - u1
    u1 = [5.5 + 5.45 * 0.2, 5.5 + c * 0.2 + 5.45 * 0.15, 5.5 + c * 0.35 + 5.45 * 0.1]
    for y, expected in zip((0.0, 0.05, 0.1), u1):
        np.testing.assert_allclose(pi.step(0.2, y), [expected, 11.0 - expected], rtol=1e-14)
    assert pi.x == pytest.approx(0.45)
    pi.reset()
    assert pi.x == 0.0
    torque = DiscretePI.from_paper("torque")
    np.testing.assert_allclose(torque.D, [7.45, -7.45])
    np.testing.assert_allclose(torque.C, [4.75e-3, -4.75e-3])


def test_pam_pi_printed_reading_clipping_and_anti_windup():
    raw = DiscretePI(5.45, 1.55, reading="printed", u_limits=None)
    raw.step(0.2, 0.0)
    np.testing.assert_allclose(raw.step(0.2, 0.05), [5.5 + 1550 * 0.2 + 5.45 * 0.15, 5.5 - 310 - 0.8175])
    clipped = DiscretePI(5.45, 1.55, reading="printed")
    clipped.step(0.2, 0.0)
    np.testing.assert_array_equal(clipped.step(0.2, 0.05), [10.0, 0.0])
    aw = DiscretePI(5.45, 1.55, reading="printed", anti_windup=True)
    for _ in range(3):
        aw.step(0.2, 0.0)
    assert aw.x == pytest.approx(0.2)    # integrated once, then frozen while saturated
    assert clipped.x == pytest.approx(0.35)
    with pytest.raises(EstimatorError, match="reading must be 'gain' or 'printed'"):
        DiscretePI(1.0, 1.0, reading="typo")
    with pytest.raises(EstimatorError, match="unknown loop 'speed'"):
        DiscretePI.from_paper("speed")
