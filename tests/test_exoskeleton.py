"""Exoskeleton (seed 004): the Fig. 6 bond graph against the paper's block diagram, eq. (3).

References: seed 004 (``docs/references.md``) (eqs. (1), (3), (5), (6), Sec. 5.1) and
``docs/exo-parameters.md`` (parameter values and status).
"""
import numpy as np
import pytest

from bondgraph import DerivationError, I, ParameterError
from plants.blockdiagram import exoskeleton as bd
from plants.library.exoskeleton import PARAMETERS, exoskeleton, parameter_values

MATRIX_RTOL = 1e-9

# every term of eq. (3) switched on (b_f, d_s, d_eh non-zero) with values away from the defaults,
# so that a wrong entry cannot hide behind a zero
ALL_TERMS = {"b_f": 0.9e-3, "d_s": 0.7, "d_eh": 3.0, "J_g": 0.6e-4, "k_s": 2.2e4, "r_g": 100.0}


def _bond_graph_in_paper_states(overrides):
    """(A, B, C, D) of the bond graph mapped by x_paper = T x_bg."""
    lm = exoskeleton(params=overrides).equations().linearize()
    T = bd.bond_graph_state_map(parameter_values(overrides))
    Ti = np.linalg.solve(T, np.eye(7))
    return lm, (T @ lm.A @ Ti, T @ lm.B, lm.C @ Ti, lm.D)


def _max_rel_diff(ref, other):
    """Largest entry-wise |other - ref| / |ref|; entries that are zero in `ref` are measured
    against the largest entry of `ref` (they must vanish to rounding)."""
    scale = np.where(ref != 0, np.abs(ref), np.max(np.abs(ref)) if ref.any() else 1.0)
    return float(np.max(np.abs(other - ref) / scale))


def test_structure_names_and_eliminated_inertia():
    eqs = exoskeleton().equations()
    assert tuple(map(str, eqs.states)) == ("p_J_m", "q_k_g", "p_J_sint", "q_k_s", "p_J_sext", "q_k_eh",
                                           "q_theta_h")
    lm = eqs.linearize()
    assert lm.inputs == ("tau_m", "w_h")
    assert lm.outputs == ("tau_s", "w_m", "tau_b", "theta_h")
    # J_m and J_g on one 1-junction (rigid shaft, Sec. 2.2): J_g is dependent storage
    assert "J_g" in str(eqs.report) and "eliminated" in str(eqs.report)


def test_parameters_carry_unit_and_source_status():
    statuses = ("PAPER", "DATASHEET", "PROXY", "ASSUMED")
    for p in PARAMETERS.values():
        assert p.unit, p.name
        assert any(s in p.description for s in statuses), p.name
    # values as in docs/exo-parameters.md (table "Parameters")
    assert parameter_values()["r_g"] == 160.0 and parameter_values()["b_g"] == 0.65
    assert parameter_values()["b_f"] == 0.48e-3 and parameter_values()["k_eh"] == 1125.0
    graph_values = exoskeleton().equations().param_values
    for name, p in PARAMETERS.items():
        assert graph_values[name] == p.value


def test_unknown_parameter_is_named():
    with pytest.raises(ParameterError, match="k_gg"):
        exoskeleton(params={"k_gg": 1.0})
    with pytest.raises(ParameterError, match="J_sext"):
        bd.state_space({k: v for k, v in parameter_values().items() if k != "J_sext"})


@pytest.mark.parametrize("overrides", [{}, {"b_f": 0.0}, ALL_TERMS], ids=["sheet", "paper-sim", "all-terms"])
def test_matrices_equal_block_diagram(overrides):
    """A, B, C, D of the bond graph equal eq. (3) + eqs. (5)-(6) after x_bd = T x_bg."""
    _, bg = _bond_graph_in_paper_states(overrides)
    ref = bd.state_space(parameter_values(overrides))
    diffs = {name: _max_rel_diff(r, m) for name, r, m in zip("ABCD", ref, bg)}
    print(f"max relative matrix difference ({overrides or 'sheet values'}): {diffs}")
    assert max(diffs.values()) < MATRIX_RTOL


def test_b_g_enters_as_b_g_over_r_g_squared():
    """Issue 3 question: eq. (1) prints b_g/r_g, eq. (3) b_g/r_g^2.  The bond graph puts R:b_g on
    the gear-output junction (w_m / r_g), so its torque b_g w_m / r_g reaches the motor through
    the TF once more: b_g / r_g^2, as in eq. (3)."""
    values = parameter_values({"b_f": 0.0})
    _, (A_bg, *_rest) = _bond_graph_in_paper_states({"b_f": 0.0})
    J1, r = values["J_m"] + values["J_g"], values["r_g"]
    squared = -(values["b_g"] + values["d_g"]) / (J1 * r**2)            # eq. (3), A(2,2)
    printed = -(values["b_g"] / r + values["d_g"] / r**2) / J1          # eq. (1) as printed
    assert A_bg[1, 1] == pytest.approx(squared, rel=MATRIX_RTOL)
    assert abs(A_bg[1, 1] - printed) > 0.5 * abs(printed)
    assert bd.state_space(values)[0][1, 1] == pytest.approx(squared, rel=1e-15)
    assert bd.state_space(values, b_g_exponent=1)[0][1, 1] == pytest.approx(printed, rel=1e-15)


def test_eigenvalues_fast_mode_and_static_gain():
    lm = exoskeleton().equations().linearize()
    eig = np.linalg.eigvals(lm.A)
    # the fast mode the issue mentions (-5.14e4 1/s with the sheet values) and the theta_h integrator
    assert -6e4 < eig.real.min() < -4e4
    assert np.min(np.abs(eig)) < 1e-9
    # statics with the trunk held (theta_h = 0, w_h = 0): the sensor carries r_g tau_m, friction is idle
    A1, B1 = lm.A[:6, :6], lm.B[:6, 0]
    x = np.linalg.solve(A1, -B1 * 0.1)
    tau_s = lm.C[0, :6] @ x
    assert tau_s == pytest.approx(160.0 * 0.1, rel=1e-12)


def test_trunk_inertia_under_imposed_velocity_is_rejected():
    """Why J_h is not in the graph: on the Sf:w_h junction it is driven by the input itself."""
    g = exoskeleton()
    g.add(I("J_h", 0.0491, domain="rotation"))
    g.connect("w_h_j", "J_h")
    with pytest.raises(DerivationError, match="J_h"):
        g.equations()


def test_zoh_is_exact_for_a_first_order_lag():
    """x' = -a x + b u, unit step: x(t) = b/a (1 - exp(-a t)) (analytic)."""
    a, b = 5e4, 2.0          # as fast as the exoskeleton's fast mode, with a coarse step
    t = np.linspace(0.0, 1e-3, 11)
    y, _ = bd.simulate_zoh(np.array([[-a]]), np.array([[b]]), np.eye(1), np.zeros((1, 1)), t, np.ones(11))
    np.testing.assert_allclose(y[:, 0], b / a * (1 - np.exp(-a * t)), rtol=1e-12, atol=1e-18)
    with pytest.raises(ValueError, match="uniformly"):
        bd.simulate_zoh(np.eye(1), np.eye(1), np.eye(1), np.zeros((1, 1)), [0.0, 0.1, 0.3], np.ones(3))


@pytest.fixture(scope="module")
def section_5_1():
    return bd.compare_section_5_1()


def test_section_5_1_bond_graph_matches_block_diagram(section_5_1):
    """Sec. 5.1: tau_m = 0.1 N m, w_h = 0.05 rad/s from 0.1 s, 1 s, b_f = 0 as in the paper."""
    c = section_5_1
    print(f"Sec. 5.1 max abs error {c.max_abs_error}, rms error {c.rms_error}")
    amplitude = {k: np.max(np.abs(v)) for k, v in c.block_diagram.items()}
    assert amplitude["tau_s"] > 20.0 and amplitude["w_m"] > 20.0     # the response of Figs. 10-11
    for k in ("tau_s", "w_m"):
        assert c.max_abs_error[k] < 1e-7 * amplitude[k]
        assert c.rms_error[k] <= c.max_abs_error[k]
    # the trunk step at 0.1 s is in both: it changes the response against a run without it
    A, B, C, D = bd.state_space(parameter_values({"b_f": 0.0}))
    y_no_trunk, _ = bd.simulate_zoh(A, B, C, D, c.t, bd.section_5_1_inputs(c.t, w_h=0.0))
    assert np.max(np.abs(y_no_trunk[:, 0] - c.block_diagram["tau_s"])) > 1.0


def test_compare_plot_writes_figure(section_5_1, tmp_path):
    path = section_5_1.plot(tmp_path / "exoskeleton_5_1.png")
    assert path.exists() and path.stat().st_size > 10_000


def test_matrix_difference_summary_used_by_the_cli():
    assert bd.matrix_difference() < MATRIX_RTOL
    assert bd.matrix_difference(ALL_TERMS) < MATRIX_RTOL
