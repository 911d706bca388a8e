"""Linear Kalman filter and steady-state observers against independent references.

References: filterpy 1.4.5 ``KalmanFilter`` (same recursions, Joseph form),
python-control 0.10 ``dlqe``/``lqe`` (Riccati gains), scipy ``cont2discrete``
(ZOH), and analytic facts (fixed points, PBH rigid-body modes).
"""
import numpy as np
import pytest
import scipy.signal

from bondgraph.errors import EstimatorError, UnobservableModeError
from estimators import (ContinuousObserver, KalmanFilter, SteadyStateKalmanFilter, continuous_kalman_gain,
                        discrete_kalman_gain, unobservable_modes)

control = pytest.importorskip("control")
filterpy_kalman = pytest.importorskip("filterpy.kalman")


def _random_system(rng, n=4, m=2, p=2, radius=0.9):
    """Random discrete system with spectral radius `radius` and random SPD Q, R."""
    F = rng.normal(size=(n, n))
    F *= radius / np.max(np.abs(np.linalg.eigvals(F)))
    B, H = rng.normal(size=(n, m)), rng.normal(size=(p, n))
    Mq, Mr = rng.normal(size=(n, n)), rng.normal(size=(p, p))
    return F, B, H, 0.1 * Mq @ Mq.T + 0.01 * np.eye(n), Mr @ Mr.T + 0.1 * np.eye(p)


def _simulate(rng, F, B, H, Q, R, N):
    n, m = B.shape
    x, xs, zs = rng.normal(size=n), [], []
    us = rng.normal(size=(N, m))
    Lq, Lr = np.linalg.cholesky(Q), np.linalg.cholesky(R)
    for k in range(N):
        zs.append(H @ x + Lr @ rng.normal(size=H.shape[0]))
        xs.append(x)
        x = F @ x + B @ us[k] + Lq @ rng.normal(size=n)
    return np.array(xs), np.array(zs), us


def test_kalman_filter_matches_filterpy_step_by_step():
    rng = np.random.default_rng(5)
    F, B, H, Q, R = _random_system(rng)
    _, zs, us = _simulate(rng, F, B, H, Q, R, 60)
    x0, P0 = rng.normal(size=4), 2.0 * np.eye(4)
    ours = KalmanFilter(F, H, Q, R, B=B, x0=x0, P0=P0)
    ref = filterpy_kalman.KalmanFilter(dim_x=4, dim_z=2, dim_u=2)
    ref.F, ref.H, ref.B, ref.Q, ref.R, ref.x, ref.P = F, H, B, Q, R, x0.copy(), P0.copy()
    for z, u in zip(zs, us):           # filterpy's order: predict, then update
        ours.predict(u)
        ref.predict(u=u)
        np.testing.assert_allclose(ours.x_prior, ref.x_prior, rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(ours.P_prior, ref.P_prior, rtol=1e-10, atol=1e-12)
        ours.update(z)
        ref.update(z)
        np.testing.assert_allclose(ours.K, ref.K, rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(ours.x_post, ref.x_post, rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(ours.P_post, ref.P_post, rtol=1e-10, atol=1e-12)
    assert np.min(np.linalg.eigvalsh(ours.P)) > 0 and np.array_equal(ours.P, ours.P.T)


def test_batch_filter_matches_filterpy_update_then_predict():
    rng = np.random.default_rng(6)
    F, B, H, Q, R = _random_system(rng, n=3, m=1, p=2)
    _, zs, us = _simulate(rng, F, B, H, Q, R, 40)
    result = KalmanFilter(F, H, Q, R, B=B).filter(zs, us)
    ref = filterpy_kalman.KalmanFilter(dim_x=3, dim_z=2, dim_u=1)
    ref.F, ref.H, ref.B, ref.Q, ref.R = F, H, B, Q, R
    ref.x, ref.P = np.zeros(3), np.eye(3)
    for k in range(len(zs)):           # our batch convention: x0, P0 are the prior of sample 0
        np.testing.assert_allclose(result.x_prior[k], ref.x, rtol=1e-10, atol=1e-12)
        ref.update(zs[k])
        np.testing.assert_allclose(result.x_post[k], ref.x, rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(result.P_post[k], ref.P, rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(result.innovation[k], ref.y, rtol=1e-10, atol=1e-12)
        ref.predict(u=us[k])


def test_steady_state_gain_is_the_limit_of_the_time_varying_filter():
    rng = np.random.default_rng(7)
    F, _, H, Q, R = _random_system(rng)
    kf = KalmanFilter(F, H, Q, R, P0=10.0 * np.eye(4))
    for _ in range(400):              # P and K do not depend on the measurements
        kf.update(np.zeros(2))
        kf.predict()
    kf.update(np.zeros(2))
    gain = discrete_kalman_gain(F, H, Q, R)
    np.testing.assert_allclose(kf.K, gain.K, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(kf.P_prior, gain.P, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(kf.P_post, gain.P_post, rtol=1e-9, atol=1e-12)
    assert np.max(np.abs(gain.poles)) < 1


def test_dare_gain_matches_python_control_dlqe():
    rng = np.random.default_rng(8)
    F, _, H, _, R = _random_system(rng)
    G = np.array([[1.0, 0.0], [2.0, -1.0], [0.0, 3.0], [-1.0, 1.0]])   # noise through G (q = 2);
    Qw = np.array([[0.5, 0.125], [0.125, 0.25]])   # binary fractions: G Qw G^T exactly symmetric for dlqe
    gain = discrete_kalman_gain(F, H, Qw, R, G=G)
    L, P, E = control.dlqe(F, G, H, Qw, R)
    np.testing.assert_allclose(gain.L, L, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(gain.P, P, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(np.sort_complex(gain.poles), np.sort_complex(E), rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(gain.L, F @ gain.K, rtol=1e-12)


def test_care_gain_matches_python_control_lqe():
    rng = np.random.default_rng(9)
    A = rng.normal(size=(4, 4)) - 3.0 * np.eye(4)
    A[0, 1] += 5.0                         # some oscillation
    C, G = rng.normal(size=(2, 4)), rng.normal(size=(4, 3))
    Qw, R = np.diag([1.0, 0.3, 2.0]), np.array([[0.2, 0.05], [0.05, 0.1]])
    gain = continuous_kalman_gain(A, C, Qw, R, G=G)
    L, P, E = control.lqe(A, G, C, Qw, R)
    np.testing.assert_allclose(gain.L, L, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(gain.P, P, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(np.sort_complex(gain.poles), np.sort_complex(E), rtol=1e-9, atol=1e-12)


def test_detectable_but_unobservable_pair_is_accepted():
    A, C = np.diag([-1.0, -2.0]), np.array([[1.0, 0.0]])     # mode -2 unseen but stable
    assert [m.eigenvalue for m in unobservable_modes(A, C)] == [-2.0]
    gain = continuous_kalman_gain(A, C, np.eye(2), [[1.0]])
    L, P, _ = control.lqe(A, np.eye(2), C, np.eye(2), [[1.0]])
    np.testing.assert_allclose(gain.L, L, rtol=1e-9, atol=1e-12)


def test_steady_state_filter_equals_kalman_filter_started_at_the_riccati_solution():
    rng = np.random.default_rng(10)
    F, B, H, Q, R = _random_system(rng)
    _, zs, us = _simulate(rng, F, B, H, Q, R, 50)
    ss = SteadyStateKalmanFilter(F, H, Q, R, B=B)
    tv = KalmanFilter(F, H, Q, R, B=B, P0=ss.gain.P)     # P stays at the DARE fixed point
    a, b = ss.filter(zs, us), tv.filter(zs, us)
    np.testing.assert_allclose(a.x_post, b.x_post, rtol=1e-9, atol=1e-10)
    np.testing.assert_allclose(a.x_prior, b.x_prior, rtol=1e-9, atol=1e-10)
    np.testing.assert_allclose(b.P_prior[-1], ss.gain.P, rtol=1e-9, atol=1e-12)


def test_continuous_observer_is_the_exact_zoh_of_the_observer_ode():
    rng = np.random.default_rng(11)
    A = rng.normal(size=(3, 3)) - 2.0 * np.eye(3)
    B, C, D = rng.normal(size=(3, 1)), rng.normal(size=(2, 3)), rng.normal(size=(2, 1))
    obs = ContinuousObserver.design(A, B, C, np.eye(3), 0.1 * np.eye(2), D=D, dt=0.01)
    L = obs.gain.L
    Ad, Bd, *_ = scipy.signal.cont2discrete((A - L @ C, np.hstack([B - L @ D, L]), np.eye(3), np.zeros((3, 3))),
                                           0.01, method="zoh")
    np.testing.assert_allclose(obs.Phi, Ad, rtol=1e-10, atol=1e-13)
    np.testing.assert_allclose(np.hstack([obs.Gamma_u, obs.Gamma_y]), Bd, rtol=1e-10, atol=1e-13)
    # at an equilibrium (constant u, y = C x_ss + D u) every estimate converges to x_ss
    u = np.array([0.7])
    x_ss = -np.linalg.solve(A, B @ u)
    est = obs.run(np.tile(u, (3000, 1)), np.tile(C @ x_ss + D @ u, (3000, 1)))
    np.testing.assert_allclose(est[-1], x_ss, rtol=1e-9, atol=1e-12)


# -- bad input -------------------------------------------------------------------------------
def _kf(**over):
    args = dict(F=np.eye(2), H=[[1.0, 0.0]], Q=np.eye(2), R=[[1.0]])
    args.update(over)
    return KalmanFilter(args.pop("F"), args.pop("H"), args.pop("Q"), args.pop("R"), **args)


@pytest.mark.parametrize("over, name, text", [
    (dict(R=[[-1.0]]), "R", "R must be symmetric positive definite; its smallest eigenvalue is -1"),
    (dict(R=[[0.0]]), "R", "R must be symmetric positive definite"),
    (dict(Q=[[1.0, 0.5], [0.0, 1.0]]), "Q", "Q must be symmetric; Q[0,1] = 0.5 but Q[1,0] = 0"),
    (dict(Q=np.diag([1.0, -0.1])), "Q", "Q must be symmetric positive semi-definite"),
    (dict(P0=np.diag([1.0, -2.0])), "P0", "P0 must be symmetric positive semi-definite"),
    (dict(H=[[1.0, 0.0, 0.0]]), "H", "H: expected shape (any, 2) but found (1, 3)"),
    (dict(R=np.eye(2)), "R", "R: expected shape (1, 1) but found (2, 2)"),
    (dict(F=[[1.0, np.nan], [0.0, 1.0]]), "F", "F has a non-finite entry at (0, 1)"),
    (dict(x0=[1.0, 2.0, 3.0]), "x0", "x0: expected shape (2,) but found (3,)"),
])
def test_bad_matrices_are_named(over, name, text):
    with pytest.raises(EstimatorError, match=text.replace("(", r"\(").replace(")", r"\)").replace("[", r"\[")
                       .replace("]", r"\]")) as info:
        _kf(**over)
    assert info.value.name == name
    assert isinstance(info.value, ValueError)


def test_bad_measurement_shape_is_named():
    with pytest.raises(EstimatorError, match=r"z: expected shape \(1,\) but found \(2,\)"):
        _kf().update([1.0, 2.0])


def test_unobservable_position_is_named_by_eigenvalue_and_state():
    # mass with velocity sensor: the position (eigenvalue 0 / z = 1) is invisible
    A, C = np.array([[0.0, 1.0], [0.0, -0.5]]), np.array([[0.0, 1.0]])
    with pytest.raises(UnobservableModeError, match=r"eigenvalue 0 .*1\*position") as info:
        continuous_kalman_gain(A, C, np.eye(2), [[1.0]], state_names=["position", "velocity"])
    assert info.value.eigenvalue == 0 and info.value.states == ("position",) and info.value.name == "C"
    F = np.array([[1.0, 0.1], [0.0, 0.95]])
    with pytest.raises(UnobservableModeError, match=r"eigenvalue 1 \(\|z\| >= 1"):
        discrete_kalman_gain(F, C, np.eye(2), [[1.0]])


def test_exoskeleton_absolute_angles_have_an_unobservable_rigid_body_mode():
    """Seed 004, eqs. (3)-(5): with motor velocity and sensor torque only, turning
    every angle together (theta_m by r_g) is invisible: eigenvalue 0."""
    from plants.blockdiagram.exoskeleton import STATES, state_space
    from plants.library.exoskeleton import parameter_values

    p = parameter_values({"b_f": 0.0})
    A, _, C, _ = state_space(p)
    C_meas = C[[0, 1]]                         # y_t, y_v (eq. (5))
    with pytest.raises(UnobservableModeError, match="eigenvalue 0 .*theta_m.*relative") as info:
        continuous_kalman_gain(A, C_meas, np.eye(7), np.eye(2), state_names=STATES)
    rigid = np.array([p["r_g"], 0, 1, 0, 1, 0, 1]) / np.hypot(p["r_g"], np.sqrt(3))
    assert abs(info.value.eigenvalue) < 1e-9
    np.testing.assert_allclose(np.abs(info.value.direction), rigid, atol=1e-9)
    # the reduced 6-state model of eq. (4) (theta_h as input) is observable from the same sensors
    assert unobservable_modes(A[:6, :6], C_meas[:, :6]) == []
