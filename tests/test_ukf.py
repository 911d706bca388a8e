"""The unscented Kalman filter (estimators.ukf) against independent references.

References: filterpy 2.0.0's UnscentedKalmanFilter (same sigma points; its
``predict`` redraws the sigma points from the prior, our ``redraw=True``; the
filterpy 1.4 behaviour, ``redraw=False``, is its ``compute_process_sigmas`` +
``unscented_transform`` without the redraw); the paper's equations (13)-(24)
of seed 000 written out in this file; the Kalman filter (exact for linear
models); the pam model simulated open loop.
"""
import numpy as np
import pytest
import scipy.linalg
from hypothesis import given
from hypothesis import strategies as st
from filterpy.kalman import JulierSigmaPoints as FpJulier
from filterpy.kalman import MerweScaledSigmaPoints as FpMerwe
from filterpy.kalman import UnscentedKalmanFilter as FpUKF
from filterpy.kalman import unscented_transform

from bondgraph.errors import EstimatorError
from bondgraph.numerics.evaluate import compile_model
from plants.library import build
from estimators import JulierSigmaPoints, MerweScaledSigmaPoints, StateMap, UnscentedKalmanFilter

DT = 1e-3          # pam sample, s (seed 000: 1 ms, 4 RK4 sub-steps)
PAM_H, PAM_M = 0.25e-3, 4
# seed 000, Sec. IV (line 317): P(0), Q, R, kappa = 0; x = (psi, dpsi, P1, P2)
PAPER_P0 = np.diag([1e-5, 1e-4, 1e6, 1e6])
PAPER_Q = np.diag([1e-5, 1e-4, 1e6, 1e6])
PAPER_R = np.diag([1e8, 1e8])


@pytest.fixture(scope="module")
def pam():
    model = compile_model(build("pam").equations())
    J = model.default_params[model.param_index["J"]]
    smap = StateMap.scaled(model.state_names, {"psi": ("q_psi", 1.0), "dpsi": ("p_J", J),
                                               "P1": ("P_1", 1.0), "P2": ("P_2", 1.0)},
                           units=("rad", "rad/s", "Pa", "Pa"))
    return model, smap


def relative_error(x, P, x_ref, P_ref):
    """Largest difference of estimates (each state relative to its largest magnitude) and
    of covariances (entry ij relative to sigma_i sigma_j, the largest standard deviations)."""
    ex = (np.abs(x - x_ref).max(axis=0) / np.abs(x_ref).max(axis=0)).max()
    s = np.sqrt(np.einsum("kii->ki", P_ref).max(axis=0))
    return max(ex, (np.abs(P - P_ref) / np.outer(s, s)).max())


def pam_recording(model, n, rng, *, x0=(3e5, 3e5, 0.0, 0.0), params=None, noise=5e3):
    """Truth (model coordinates) and noisy P1, P2 under sinusoidal valve voltages."""
    t = np.arange(n) * DT
    u = np.column_stack([5 + 4 * np.sin(2 * np.pi * t), 5 - 4 * np.sin(2 * np.pi * 0.7 * t)])
    p = model.param_vector(params)
    x, d = np.array(x0, dtype=float), model.default_held.copy()
    X = np.empty((n, 4))
    X[0] = x
    for k in range(1, n):
        x, d = model.rk4_step(x, u[k - 1], t0=t[k - 1], h=PAM_H, substeps=PAM_M, d=d, p=p)
        X[k] = x
    z = X[:, :2] + rng.normal(0.0, noise, (n, 2))
    return u, z, X


# -- a small nonlinear model in Python ----------------------------------------------------

def toy_fx(X, u):
    """Damped pendulum, one explicit-Euler sample of 0.05 s; batched (N, 2)."""
    th, om = X[:, 0], X[:, 1]
    return np.column_stack([th + 0.05 * om, om + 0.05 * (-4.0 * np.sin(th) - 0.3 * om + u)])


def toy_hx(X, u):
    return np.column_stack([np.sin(X[:, 0]) + 0.1 * X[:, 1] ** 2, X[:, 0] * X[:, 1]])


TOY = dict(x0=np.array([0.8, -0.2]), P0=np.diag([0.2, 0.3]), Q=np.array([[1e-3, 2e-4], [2e-4, 2e-3]]),
           R=np.diag([0.01, 0.02]))


def toy_data(rng, n=60):
    x, zs = np.array([1.0, 0.0]), []
    for k in range(n):
        x = toy_fx(x[None], 0.5)[0] + rng.normal(0, 0.02, 2)
        zs.append(toy_hx(x[None], 0.5)[0] + rng.normal(0, 0.1, 2))
    return np.array(zs)


def filterpy_run(fp, zs, redraw, fx_args_of):
    """Run filterpy; ``redraw=False`` is the filterpy 1.4 predict (no redraw)."""
    xs, Ps = [], []
    for k, z in enumerate(zs):
        if redraw:
            fp.predict(**fx_args_of(k, fp))
        else:
            fp.compute_process_sigmas(fp._dt, **fx_args_of(k, fp))
            fp.x, fp.P = unscented_transform(fp.sigmas_f, fp.Wm, fp.Wc, fp.Q)
        fp.update(z)
        xs.append(fp.x.copy())
        Ps.append(fp.P.copy())
    return np.array(xs), np.array(Ps)


POINTS = [("julier-k0", lambda n: (JulierSigmaPoints(n, kappa=0.0), FpJulier(n, kappa=0.0))),
          ("julier-k1", lambda n: (JulierSigmaPoints(n, kappa=1.0), FpJulier(n, kappa=1.0))),
          ("merwe", lambda n: (MerweScaledSigmaPoints(n, alpha=0.3, beta=2.0, kappa=0.0),
                               FpMerwe(n, alpha=0.3, beta=2.0, kappa=0.0)))]


@pytest.mark.parametrize("redraw", [True, False])
@pytest.mark.parametrize("name,make", POINTS, ids=[p[0] for p in POINTS])
def test_toy_model_matches_filterpy(name, make, redraw, rng):
    ours_pts, fp_pts = make(2)
    np.testing.assert_allclose(ours_pts.Wm, fp_pts.Wm, rtol=1e-15)
    np.testing.assert_allclose(ours_pts.Wc, fp_pts.Wc, rtol=1e-15)
    zs = toy_data(rng)
    ukf = UnscentedKalmanFilter(fx=toy_fx, hx=toy_hx, points=ours_pts, redraw=redraw, **TOY)
    fp = FpUKF(dim_x=2, dim_z=2, dt=0.05, points=fp_pts,
               fx=lambda x, dt, u: toy_fx(x[None], u)[0], hx=lambda x: toy_hx(x[None], 0.5)[0])
    fp.x, fp.P, fp.Q, fp.R = TOY["x0"].copy(), TOY["P0"].copy(), TOY["Q"], TOY["R"]
    xs, Ps = filterpy_run(fp, zs, redraw, lambda k, f: {"u": 0.5})
    for k, z in enumerate(zs):
        ukf.step(0.5, z)
        np.testing.assert_allclose(ukf.x, xs[k], rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(ukf.P, Ps[k], rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("redraw", [True, False])
@pytest.mark.parametrize("kernel", ["c", "numpy"])
@pytest.mark.parametrize("name,make", POINTS[::2], ids=[p[0] for p in POINTS[::2]])
def test_pam_matches_filterpy(pam, name, make, kernel, redraw, rng):
    """filterpy's fx calls our compiled model row by row; the held friction torque
    follows the central point (the policy of estimators.ukf_model)."""
    model, smap = pam
    n = 150
    u, z, _ = pam_recording(model, n, rng)
    ours_pts, fp_pts = make(4)
    x0 = np.array([0.02, 0.0, 2.9e5, 3.1e5])
    ukf = UnscentedKalmanFilter.from_model(model, dt=DT, outputs=("P1", "P2"), x0=x0, P0=PAPER_P0,
                                           Q=PAPER_Q, R=PAPER_R, points=ours_pts, redraw=redraw,
                                           state_map=smap, kernel=kernel)
    assert ukf.kernel == kernel
    res = ukf.batch_filter(z, u)

    held = {"d": model.default_held.copy()}

    def fx(x, dt, u, d):
        return smap.to_filter(model.rk4_step(smap.to_model(x), u, h=PAM_H, substeps=PAM_M, d=d)[0])

    def hx(x):
        return model.h(smap.to_model(x), d=held["d"])[[1, 2]]

    def fx_args(k, f):   # inputs u[k], held values of the central point (the posterior mean)
        d_now = held["d"]
        held["d"] = model.rk4_step(smap.to_model(f.x), u[k], h=PAM_H, substeps=PAM_M, d=d_now)[1]
        return {"u": u[k], "d": d_now}

    fp = FpUKF(dim_x=4, dim_z=2, dt=DT, points=fp_pts, fx=fx, hx=hx)
    fp.x, fp.P, fp.Q, fp.R = x0.copy(), PAPER_P0.copy(), PAPER_Q, PAPER_R
    xs, Ps = filterpy_run(fp, z[1:], redraw, fx_args)
    assert relative_error(res.x[1:], res.P[1:], xs, Ps) < 1e-9


def test_c_kernel_equals_numpy_reference(pam, rng):
    model, smap = pam
    u, z, _ = pam_recording(model, 400, rng)
    out = {}
    for kernel in ("c", "numpy"):
        ukf = UnscentedKalmanFilter.from_model(model, dt=DT, outputs=("P1", "P2"),
                                               x0=[0.0, 0.0, 1.013e5, 1.013e5], P0=PAPER_P0, Q=PAPER_Q,
                                               R=PAPER_R, points=JulierSigmaPoints(4), state_map=smap,
                                               kernel=kernel)
        out[kernel] = ukf.batch_filter(z, u)
    assert relative_error(out["c"].x, out["c"].P, out["numpy"].x, out["numpy"].P) < 1e-12


# -- the paper's equations, written out -------------------------------------------------------

def paper_ukf(fx, hx, x, P, Q, R, kappa, us, zs):
    """Eqs. (13)-(24) of seed 000, loop by loop; sigma points redrawn before eq. (19)."""
    n = x.size
    W = np.full(2 * n + 1, 1.0 / (2 * (n + kappa)))
    W[0] = kappa / (n + kappa)

    def sigmas(m, C):
        root = scipy.linalg.cholesky((n + kappa) * C)        # upper: rows are the square roots
        return [m] + [m + root[i] for i in range(n)] + [m - root[i] for i in range(n)]

    xs, Ps = [], []
    for u, z in zip(us, zs):
        Xm = [fx(s, u) for s in sigmas(x, P)]                                      # (16)
        x_pr = sum(W[i] * Xm[i] for i in range(2 * n + 1))                         # (17)
        P_pr = sum(W[i] * np.outer(Xm[i] - x_pr, Xm[i] - x_pr) for i in range(2 * n + 1)) + Q   # (18)
        Xr = sigmas(x_pr, P_pr)                                                    # redraw
        Y = [hx(s, u) for s in Xr]                                                 # (19)
        y_pr = sum(W[i] * Y[i] for i in range(2 * n + 1))                          # (20)
        Pyy = sum(W[i] * np.outer(Y[i] - y_pr, Y[i] - y_pr) for i in range(2 * n + 1)) + R      # (21)
        Pxy = sum(W[i] * np.outer(Xr[i] - x_pr, Y[i] - y_pr) for i in range(2 * n + 1))         # (22)
        K = Pxy @ np.linalg.inv(Pyy)
        x = x_pr + K @ (z - y_pr)                                                  # (23)
        P = P_pr - K @ Pyy @ K.T                                                   # (24)
        xs.append(x)
        Ps.append(P)
    return np.array(xs), np.array(Ps)


@pytest.mark.parametrize("kappa", [0.0, 1.0])
def test_toy_model_matches_paper_equations(kappa, rng):
    zs = toy_data(rng, 40)
    ukf = UnscentedKalmanFilter(fx=toy_fx, hx=toy_hx, points=JulierSigmaPoints(2, kappa=kappa), **TOY)
    res = ukf.batch_filter(np.vstack([np.zeros(2), zs]), [0.5] * (len(zs) + 1))
    xs, Ps = paper_ukf(lambda s, u: toy_fx(s[None], u)[0], lambda s, u: toy_hx(s[None], u)[0],
                       TOY["x0"], TOY["P0"], TOY["Q"], TOY["R"], kappa, [0.5] * len(zs), zs)
    np.testing.assert_allclose(res.x[1:], xs, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(res.P[1:], Ps, rtol=1e-9, atol=1e-12)


def test_pam_c_kernel_matches_paper_equations(pam, rng):
    model, smap = pam
    u, z, _ = pam_recording(model, 120, rng)
    x0 = np.array([0.0, 0.0, 2.9e5, 3.1e5])
    ukf = UnscentedKalmanFilter.from_model(model, dt=DT, outputs=("P1", "P2"), x0=x0, P0=PAPER_P0,
                                           Q=PAPER_Q, R=PAPER_R, points=JulierSigmaPoints(4, kappa=0.0),
                                           state_map=smap, kernel="c")
    res = ukf.batch_filter(z, u)
    d = {"v": model.default_held.copy()}   # held values: row 0 of the sigma points is the mean

    def fx(s, uk):
        xm, dn = model.rk4_step(smap.to_model(s), uk, h=PAM_H, substeps=PAM_M, d=d["v"])
        return smap.to_filter(xm)

    xs, Ps = paper_ukf(fx, lambda s, uk: s[2:4], x0, PAPER_P0, PAPER_Q, PAPER_R, 0.0, u[:-1], z[1:])
    assert relative_error(res.x[1:], res.P[1:], xs, Ps) < 1e-9


# -- linear models: the UKF is the Kalman filter --------------------------------------------

def kalman(A, B, C, Q, R, x, P, us, zs):
    """Discrete Kalman filter: x- = A x + B u, P- = A P A' + Q; K = P- C' (C P- C' + R)^-1."""
    xs, Ps = [], []
    for u, z in zip(us, zs):
        x, P = A @ x + B @ u, A @ P @ A.T + Q
        S = C @ P @ C.T + R
        K = np.linalg.solve(S, C @ P).T
        x, P = x + K @ (z - C @ x), P - K @ S @ K.T
        xs.append(x)
        Ps.append(P)
    return np.array(xs), np.array(Ps)


@pytest.mark.parametrize("points", [JulierSigmaPoints(3, kappa=0.0), JulierSigmaPoints(3, kappa=2.0),
                                    MerweScaledSigmaPoints(3, alpha=0.5, beta=2.0, kappa=0.0)],
                         ids=["julier-k0", "julier-k2", "merwe"])
def test_linear_python_model_equals_kalman_filter(points, rng):
    A = np.array([[0.9, 0.1, 0.0], [-0.2, 0.8, 0.1], [0.0, 0.05, 0.95]])
    B = np.array([[0.0], [0.1], [0.05]])
    C = np.array([[1.0, 0.0, 0.5], [0.0, 1.0, 0.0]])
    Q, R = np.diag([1e-3, 2e-3, 1e-3]), np.array([[0.05, 0.01], [0.01, 0.04]])
    x0, P0 = np.array([1.0, -1.0, 0.5]), np.diag([1.0, 2.0, 0.5])
    us = rng.normal(size=(50, 1))
    zs = rng.normal(size=(50, 2))
    ukf = UnscentedKalmanFilter(fx=lambda X, u: X @ A.T + u @ B.T, hx=lambda X, u: X @ C.T,
                                x0=x0, P0=P0, Q=Q, R=R, points=points)
    res = ukf.batch_filter(np.vstack([np.zeros(2), zs]), np.vstack([us, np.zeros((1, 1))]))
    xs, Ps = kalman(A, B, C, Q, R, x0, P0, us, zs)
    np.testing.assert_allclose(res.x[1:], xs, rtol=0, atol=1e-10)
    np.testing.assert_allclose(res.P[1:], Ps, rtol=0, atol=1e-10)


@pytest.mark.parametrize("kernel", ["c", "numpy"])
def test_linear_bond_graph_equals_kalman_filter(kernel, rng):
    """mass-spring-damper: RK4 over one sample of a linear model is x+ = Phi x + Gamma u with
    Phi, Gamma the 4th-order Taylor polynomials of the exact discretisation."""
    lin = build("mass-spring-damper").equations().linearize()
    A, B, C = np.asarray(lin.A, float), np.asarray(lin.B, float), np.asarray(lin.C, float)
    h, m = 0.02, 3
    Ah = A * h
    Phi1 = sum(np.linalg.matrix_power(Ah, j) / f for j, f in enumerate((1, 1, 2, 6, 24)))
    Gam1 = sum(np.linalg.matrix_power(Ah, j - 1) * h / f for j, f in ((1, 1), (2, 2), (3, 6), (4, 24))) @ B
    Phi, Gam = np.linalg.matrix_power(Phi1, m), sum(np.linalg.matrix_power(Phi1, j) for j in range(m)) @ Gam1
    Q, R = np.diag([1e-4, 2e-4]), np.array([[1e-3, 2e-4], [2e-4, 2e-3]])
    x0, P0 = np.array([0.3, -0.1]), np.diag([0.5, 0.2])
    n = 80
    us, zs = rng.normal(size=(n, 1)), rng.normal(scale=0.1, size=(n, 2))
    ukf = UnscentedKalmanFilter.from_model(build("mass-spring-damper"), dt=h * m, substeps=m,
                                           outputs=("x", "v"), x0=x0, P0=P0, Q=Q, R=R,
                                           points=MerweScaledSigmaPoints(2, alpha=0.7), kernel=kernel)
    res = ukf.batch_filter(zs, us)
    xs, Ps = kalman(Phi, Gam, C, Q, R, x0, P0, us[:-1], zs[1:])
    np.testing.assert_allclose(res.x[1:], xs, rtol=0, atol=1e-10)
    np.testing.assert_allclose(res.P[1:], Ps, rtol=0, atol=1e-10)


# -- the paper's use: psi from P1, P2 --------------------------------------------------------

def test_pam_ukf_estimates_angle_better_than_the_model_alone(pam, rng):
    """Truth: perturbed orifice areas and shaft friction, psi(0) = 0; filter and open-loop
    model: nominal parameters, psi(0) = 10 deg and pressures 100 kPa off.  Measured: P1, P2
    with 5 kPa noise.  (Measured here: RMSE after 0.5 s about 0.6 deg for the UKF, 3.9 deg
    for the model alone.)"""
    model, smap = pam
    n = 1500
    truth = {"A1": 5.184e-8 * 1.2, "A2": 7.776e-8 * 0.85, "mu_s": 0.3}
    u, z, X = pam_recording(model, n, rng, params=truth)
    wrong = np.array([np.radians(10.0), 0.0, 2e5, 4e5])
    x, d = smap.to_model(wrong), model.default_held.copy()
    psi_open = np.empty(n)
    psi_open[0] = x[3]
    for k in range(1, n):
        x, d = model.rk4_step(x, u[k - 1], h=PAM_H, substeps=PAM_M, d=d)
        psi_open[k] = x[3]
    ukf = UnscentedKalmanFilter.from_model(model, dt=DT, outputs=("P1", "P2"), x0=wrong, P0=PAPER_P0,
                                           Q=PAPER_Q, R=PAPER_R, points=JulierSigmaPoints(4), state_map=smap)
    res = ukf.batch_filter(z, u)
    late = slice(500, n)
    rmse_ukf = np.sqrt(np.mean(np.degrees(res["psi"] - X[:, 3])[late] ** 2))
    rmse_open = np.sqrt(np.mean(np.degrees(psi_open - X[:, 3])[late] ** 2))
    assert rmse_ukf < 1.2
    assert rmse_open > 2.5
    assert rmse_ukf < rmse_open / 3
    assert np.isfinite(res.P).all() and (np.linalg.eigvalsh(res.P) > 0).all()


# -- bad input --------------------------------------------------------------------------------

def make_toy(**over):
    args = dict(TOY, fx=toy_fx, hx=toy_hx, points=JulierSigmaPoints(2))
    args.update(over)
    return UnscentedKalmanFilter(**args)


@pytest.mark.parametrize("over,name,text", [
    ({"P0": np.diag([1.0, -1.0])}, "P0", "not positive definite"),
    ({"R": np.array([[1.0, 2.0], [2.0, 1.0]])}, "R", "not positive definite"),
    ({"Q": np.array([[1.0, 0.5], [0.0, 1.0]])}, "Q", "not symmetric"),
    ({"Q": -np.eye(2)}, "Q", "not positive semidefinite"),
    ({"P0": np.eye(3)}, "P0", "expected shape (2, 2)"),
    ({"x0": [0.0, np.nan]}, "x0", "non-finite"),
    ({"R": np.array([1.0, 1.0])}, "R", "square matrix"),
    ({"points": JulierSigmaPoints(3)}, "points", "n = 3"),
])
def test_bad_setup_names_the_matrix(over, name, text):
    with pytest.raises(EstimatorError, match="UKF set-up") as err:
        make_toy(**over)
    assert err.value.name == name
    assert any(text in p for p in err.value.problems)


def test_every_setup_problem_is_listed():
    with pytest.raises(EstimatorError) as err:
        make_toy(P0=np.diag([1.0, -1.0]), R=np.full((2, 2), np.nan))
    assert [p.split(":")[0] for p in err.value.problems] == ["P0", "R"]
    assert isinstance(err.value, ValueError)


def test_bad_measurements_are_named(pam, rng):
    ukf = make_toy()
    with pytest.raises(EstimatorError, match=r"z: non-finite entries y1") as err:
        ukf.step(0.5, [0.1, np.nan])
    assert err.value.name == "z" and ukf.k == 0     # nothing was done
    with pytest.raises(EstimatorError, match=r"z: expected shape \(2,\)"):
        ukf.update([1.0, 2.0, 3.0])
    model, smap = pam
    f = UnscentedKalmanFilter.from_model(model, dt=DT, outputs=("P1", "P2"), x0=[0, 0, 3e5, 3e5],
                                         P0=PAPER_P0, Q=PAPER_Q, R=PAPER_R, points=JulierSigmaPoints(4),
                                         state_map=smap, kernel="c")
    u_before = f._e._v["u"].copy()
    with pytest.raises(EstimatorError, match=r"z: non-finite entries P1") as err:
        f.step([1.0, 2.0], [np.nan, 3e5])
    assert err.value.name == "z" and f.k == 0 and (f._e._v["u"] == u_before).all()
    with pytest.raises(EstimatorError, match=r"u: expected shape \(2,\) \(u1, u2\)"):
        f.step([1.0, 2.0, 3.0], [3e5, 3e5])
    z = np.full((5, 2), 3e5)
    z[3, 1] = np.nan
    with pytest.raises(EstimatorError, match=r"z\[3, 1\] \(P2\) is not finite"):
        f.batch_filter(z, np.full((5, 2), 5.0))
    with pytest.raises(EstimatorError, match=r"u must have shape \(5, 2\) \(u1, u2\)"):
        f.batch_filter(np.full((5, 2), 3e5), np.zeros((5, 3)))
    with pytest.raises(EstimatorError, match=r"u: non-finite entries u2"):
        f.predict([1.0, np.inf])


@pytest.mark.parametrize("kernel", ["c", "numpy"])
def test_model_failure_is_an_error_not_a_nan(pam, kernel):
    """A covariance so wide (1e200 Pa^2) that the model overflows at some sigma points:
    reported by step and sigma point, not propagated as NaN."""
    model, smap = pam
    f = UnscentedKalmanFilter.from_model(model, dt=DT, outputs=("P1", "P2"), x0=[0, 0, 3e5, 3e5],
                                         P0=np.diag([1e-5, 1e-4, 1e200, 1e200]), Q=PAPER_Q, R=PAPER_R,
                                         points=JulierSigmaPoints(4), state_map=smap, kernel=kernel)
    with pytest.raises(EstimatorError, match=r"step 0 .*non-finite .*sigma point") as err:
        f.step([5.0, 5.0], [3e5, 3e5])
    assert err.value.name == "fx" and err.value.step == 0


def test_lost_positive_definiteness_names_the_matrix():
    """Julier points with kappa < 0 give W0 < 0: the prior covariance of a strongly
    nonlinear map can become indefinite; the redraw then fails on P_prior."""
    # points 0, +-sqrt(0.5) with weights -1, 1, 1 -> squares 0, 0.5, 0.5: mean 1, P- = -1 + 0.5
    ukf = UnscentedKalmanFilter(fx=lambda X, u: X ** 2, hx=lambda X, u: X, x0=[0.0], P0=[[1.0]],
                                Q=[[0.0]], R=[[1.0]], points=JulierSigmaPoints(1, kappa=-0.5))
    with pytest.raises(EstimatorError, match=r"P⁻ is not positive definite") as err:
        ukf.step(None, [1.0])
    assert err.value.name == "P_prior" and err.value.step == 1


def test_state_map_and_options_are_checked(pam):
    model, _ = pam
    with pytest.raises(EstimatorError, match="missing"):
        StateMap.scaled(model.state_names, {"psi": ("q_psi", 1.0)})
    with pytest.raises(EstimatorError, match="singular"):
        StateMap(np.zeros((2, 2)), ("a", "b"))
    with pytest.raises(EstimatorError, match="kernel must be one of"):
        UnscentedKalmanFilter.from_model(model, dt=DT, outputs=("P1",), x0=np.zeros(4), P0=np.eye(4),
                                         Q=np.eye(4), R=np.eye(1), points=JulierSigmaPoints(4), kernel="fortran")
    with pytest.raises(Exception, match="unknown output 'P3'"):
        UnscentedKalmanFilter.from_model(model, dt=DT, outputs=("P3",), x0=np.zeros(4), P0=np.eye(4),
                                         Q=np.eye(4), R=np.eye(1), points=JulierSigmaPoints(4))


def test_models_with_algebraic_loops_use_the_numpy_engine(capsys):
    graph = build("resistor-loop-nl")
    eqs = graph.equations()
    assert eqs.algebraic   # a loop solved by Newton's method at each evaluation
    n, outputs = len(eqs.states), ("v_C",)
    args = dict(dt=0.01, outputs=outputs, x0=np.zeros(n), P0=np.eye(n), Q=1e-4 * np.eye(n),
                R=[[1e-2]], points=JulierSigmaPoints(n))
    ukf = UnscentedKalmanFilter.from_model(graph, **args)
    assert ukf.kernel == "numpy"
    res = ukf.batch_filter(np.full((30, 1), 0.5), progress=True)
    assert np.isfinite(res.x).all() and res.std.shape == (30, n)
    assert "ukf: 100.0 %" in capsys.readouterr().err
    with pytest.raises(EstimatorError, match="algebraic unknowns") as err:
        UnscentedKalmanFilter.from_model(graph, kernel="c", **args)
    assert err.value.name == "kernel"


@given(st.floats(0.05, 5.0), st.floats(-0.9, 0.9), st.floats(1e-4, 1.0), st.floats(1e-3, 1.0),
       st.sampled_from([0.0, 1.0, 3.0]))
def test_covariance_stays_symmetric_positive_definite(p0, rho, q, r, kappa):
    """Invariant: after every update P is exactly symmetric and positive definite."""
    P0 = p0 * np.array([[1.0, rho], [rho, 1.0]])
    ukf = UnscentedKalmanFilter(fx=toy_fx, hx=toy_hx, x0=[0.3, 0.0], P0=P0, Q=q * np.eye(2),
                                R=r * np.eye(2), points=JulierSigmaPoints(2, kappa=kappa))
    zs = np.random.default_rng(7).normal(size=(15, 2))
    for z in zs:
        ukf.step(0.1, z)
        P = ukf.P
        assert (P == P.T).all()
        assert np.linalg.eigvalsh(P).min() > 0


def test_benchmark_runs_once(load_script, capsys):
    bench = load_script("benchmarks/ukf.py")
    bench.main(steps=20, repeats=1, python_steps=2)
    out = capsys.readouterr().out
    assert "filterpy" in out and "us/step" in out
