"""diagnosis.locate: significant time windows and the operating regime of a mismatch."""
import numpy as np
import pytest

from plants import library
from diagnosis.errors import DiagnosisError
from diagnosis.locate import locate_regime, regime_variables, significant_windows
from diagnosis.recording import Experiment
from diagnosis.residuals import OutputSimulator


def test_window_found_where_a_bump_exceeds_the_noise():
    rng = np.random.default_rng(3)
    t = np.arange(0.0, 10.0, 1e-3)
    sigma = 0.01
    r = rng.normal(0.0, sigma, t.size) + np.where((t >= 3.0) & (t < 4.0), 0.02, 0.0)
    windows = significant_windows(t, r, sigma)
    assert len(windows) == 1
    t0, t1 = windows[0]
    # w = 50 samples (n // 200): edges within a window length of the truth
    assert t0 == pytest.approx(3.0, abs=0.06) and t1 == pytest.approx(4.0, abs=0.06)


def test_no_window_in_pure_noise():
    rng = np.random.default_rng(4)
    t = np.arange(0.0, 30.0, 1e-3)
    assert significant_windows(t, rng.normal(0.0, 0.05, t.size), 0.05) == []
    with pytest.raises(DiagnosisError, match="same length"):
        significant_windows(t, t[:-1], 0.1)


@pytest.fixture(scope="module")
def msd_run():
    t = np.linspace(0.0, 10.0, 2001)
    exp = Experiment(t, {"F": np.sin(2 * np.pi * 0.5 * t)}, {"x": t.copy()}, {"F": "N", "x": "m"})
    graph = library.build("mass-spring-damper")
    return graph, exp, OutputSimulator(graph, exp).run()


def test_regime_variables_are_velocities_efforts_and_inputs(msd_run):
    graph, exp, run = msd_run
    rv = regime_variables(graph, exp, run)
    assert set(rv) == {"v_m", "e_k", "F"}
    p, q = run.states[:, 0], run.states[:, 1]
    np.testing.assert_allclose(rv["v_m"][0], p / 1.0, rtol=1e-12)   # v = p/m, m = 1 kg
    np.testing.assert_allclose(rv["e_k"][0], 4.0 * q, rtol=1e-12)   # F_k = k q, k = 4 N/m
    assert rv["v_m"][1] == "velocity of m (m/s)" and rv["e_k"][1] == "force in k (N)"
    np.testing.assert_array_equal(rv["F"][0], exp.inputs["F"])
    # with StateEquations only the states and inputs are known
    assert set(regime_variables(graph.equations(), exp, run.states)) == {"p_m", "q_k", "F"}
    with pytest.raises(DiagnosisError, match="states of shape"):
        regime_variables(graph, exp, run.states[:, :1])


def test_coulomb_like_signal_is_placed_on_the_velocity_sign(msd_run):
    graph, exp, run = msd_run
    rv = regime_variables(graph, exp, run)
    v = rv["v_m"][0]
    rng = np.random.default_rng(5)
    noise = rng.normal(0.0, 0.01, v.size)
    stuck = np.abs(v) <= 0.02 * np.sqrt(np.mean(v ** 2))   # the "near zero" class
    signal = np.where(stuck, 0.0, -0.3 * np.sign(v)) + noise
    found = locate_regime(signal, rv, unit="N")
    assert (found.variable, found.feature) == ("v_m", "sign")
    # the class means explain everything but the noise: R^2 = 1 - sigma^2 / var
    assert found.explained == pytest.approx(1 - 0.01 ** 2 / np.var(signal), abs=2e-4)
    assert "-0.3 N when v_m > 0" in found.description and "+0.3 N when v_m < 0" in found.description


def test_stiffening_signal_is_placed_on_the_spring_force_magnitude(msd_run):
    graph, exp, run = msd_run
    rv = regime_variables(graph, exp, run)
    found = locate_regime(5.0 * rv["e_k"][0] ** 2, rv)
    assert (found.variable, found.feature) == ("e_k", "magnitude")
    assert found.explained > 0.9 and "grows with |e_k|" in found.description
    with pytest.raises(DiagnosisError, match="regime variable 'v_m' has"):
        locate_regime(np.zeros(5), rv)
