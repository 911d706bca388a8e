"""Model Exchange partials: directional derivatives (symbolic Jacobians compiled into the
FMU) against finite differences of the FMU's own derivatives, against bondgraph's
linearisation and against the analytic matrices of the mass-spring-damper; event
indicators that change sign where a law switches, located by fmpy's CVode."""
from __future__ import annotations

import zipfile

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.fmi1 import FMICallException

from bondgraph.numerics import simulate
import plants.library as library

from fmu_helpers import Model

VERSIONS = (2, 3)
#: Operating points away from every switching surface (states, then inputs; the valve
#: tables of pam have breakpoints every 0.5 V).
POINTS = {
    "mass-spring-damper": {"p_m": 0.3, "q_k": -0.02, "F": 2.0},
    "dc-motor": {"p_L": 1e-3, "p_J": 2e-3, "V": 12.0, "tau_L": 0.01},
    "pam-frictionless": {"P_1": 3.0e5, "P_2": 2.0e5, "q_psi": 0.1, "p_J": 0.01, "u1": 6.8, "u2": 3.2},
    "resistor-loop-nl": {"V": 3.0},
}


@pytest.fixture(scope="module")
def fmus(exported_fmu):
    return exported_fmu


def _jacobian(m, eqs):
    """J = d(der(x), y)/d(x, u) by unit seeds, through fmiGetDirectionalDerivative."""
    unknowns = [f"der({s})" for s in eqs.state_names] + list(eqs.outputs)
    knowns = list(eqs.state_names) + list(eqs.input_names)
    return np.column_stack([m.directional(unknowns, knowns, np.eye(len(knowns))[k])
                            for k in range(len(knowns))]) if knowns else np.zeros((len(unknowns), 0))


def _at_point(m, eqs, point):
    m.start({k: v for k, v in point.items() if k in eqs.input_names})
    x = m.x()
    for i, s in enumerate(m.state_names):
        x[i] = point.get(s, x[i])
    m.set_x(x)
    return x


@pytest.mark.parametrize("version", VERSIONS)
@pytest.mark.parametrize("model", list(POINTS))
def test_directional_derivatives_match_linearisation_and_finite_differences(fmus, model, version):
    path = fmus(model, version)
    with zipfile.ZipFile(path) as z:   # fmpy 0.3.32 reads FMI 3.0's plural attribute as the singular
        xml = z.read("modelDescription.xml").decode()
    flag = "providesDirectionalDerivative" + ("" if version == 2 else "s") + '="true"'
    assert xml.count(flag) == 2   # ModelExchange and CoSimulation
    eqs = library.build(model).equations()
    point = POINTS[model]
    m = Model(path)
    try:
        x = _at_point(m, eqs, point)
        J = _jacobian(m, eqs)
        # reference 1: bondgraph's linearisation (lambdified sympy Jacobians, numpy)
        lin = eqs.linearize({**dict(zip(m.state_names, x)),
                             **{k: v for k, v in point.items() if k in eqs.input_names}})
        ref = np.block([[np.asarray(lin.A, float), np.asarray(lin.B, float)],
                        [np.asarray(lin.C, float), np.asarray(lin.D, float)]])
        scale = np.maximum(np.abs(ref).max(axis=1, keepdims=True), 1e-300)
        assert np.allclose(J, ref, rtol=0, atol=1e-11 * scale)
        # reference 2: central differences of the FMU's own derivatives (states only)
        nx = len(x)
        for j in range(nx):
            eps = 1e-6 * max(1.0, abs(x[j]))
            cols = []
            for sgn in (1, -1):
                xp = x.copy()
                xp[j] += sgn * eps
                m.set_x(xp)
                cols.append(m.dx())
            m.set_x(x)
            fd = (cols[0] - cols[1]) / (2 * eps)
            assert np.allclose(J[:nx, j], fd, rtol=1e-6, atol=1e-7 * scale[:nx, 0]), (j, J[:nx, j], fd)
    finally:
        m.close()


@pytest.mark.parametrize("version", VERSIONS)
def test_mass_spring_damper_jacobian_is_the_analytic_one(fmus, version):
    # m p' = ..: p_m' = F - k q_k - b p_m / m,  q_k' = p_m / m  (Karnopp, Margolis, Rosenberg ch. 3)
    eqs = library.build("mass-spring-damper").equations()
    mass, k, b = (eqs.param_values[n] for n in "mkb")
    m = Model(fmus("mass-spring-damper", version))
    try:
        _at_point(m, eqs, POINTS["mass-spring-damper"])
        J = _jacobian(m, eqs)
        order = list(eqs.state_names)
        A = np.zeros((2, 2))
        A[order.index("p_m"), order.index("p_m")] = -b / mass
        A[order.index("p_m"), order.index("q_k")] = -k
        A[order.index("q_k"), order.index("p_m")] = 1 / mass
        assert np.allclose(J[:2, :2], A, rtol=1e-14, atol=0)
        assert np.allclose(J[order.index("p_m"), 2], 1.0) and J[order.index("q_k"), 2] == 0.0
        with pytest.raises(FMICallException):   # parameters are not knowns
            m.directional(["der(p_m)"], ["m"], [1.0])
        assert "only states and inputs" in m.messages[-1]
    finally:
        m.close()


@pytest.mark.parametrize("version", VERSIONS)
def test_event_indicators_locate_the_choked_flow_switches(fmus, version):
    # Muscle 1 vents from 5 bar, muscle 2 fills from the tank (pam-locked, u1 = 0, u2 = 9.8 V).
    # The orifice law switches from choked to subsonic flow where the pressure ratio passes
    # the critical (2/(k+1))^(k/(k-1)) = 0.5283 (k = 1.4; seed 000 eq. (5)): fmpy's CVode,
    # stopping at the FMU's event indicators, must find those times on the reference trajectory.
    path = fmus("pam-locked", version)
    md = read_model_description(str(path))
    assert md.numberOfEventIndicators == 52   # 2 valves x (20 table rows + 6 flow switches)
    p = library.build("pam-locked").equations().param_values
    me = simulate_fmu(str(path), stop_time=3.0, output_interval=1e-3, fmi_type="ModelExchange",
                      start_values={"u1": 0.0, "u2": 9.8, "P_1": 5e5}, relative_tolerance=1e-10,
                      record_events=True, output=["P_1", "P_2"])
    t = me["time"]
    events = np.unique(t[1:][np.diff(t) == 0.0])
    ref = simulate(library.build("pam-locked"), (0.0, 3.0), inputs={"u1": 0.0, "u2": 9.8},
                      x0={"P_1": 5e5}, rtol=1e-11, atol=1e-6, output_interval=1e-3)
    crit = (2 / (p["k"] + 1)) ** (p["k"] / (p["k"] - 1))
    t_fill = np.interp(crit * p["P_tank"], ref["P_2"], ref.t)     # P_2 / P_tank rises past crit
    t_vent = np.interp(-p["P_out"] / crit, -ref["P_1"], ref.t)    # P_out / P_1 rises past crit
    assert 1.0 < t_fill < t_vent < 2.9
    for t_switch in (t_fill, t_vent):
        assert np.min(np.abs(events - t_switch)) < 1e-5, (t_switch, events)
    keep = np.r_[True, np.diff(t) > 0]
    for name in ("P_1", "P_2"):
        got = np.interp(ref.t, t[keep], me[name][keep])
        assert np.allclose(got, ref[name], rtol=1e-8, atol=0), name


@pytest.mark.parametrize("version", VERSIONS)
def test_event_indicators_are_the_switching_functions(fmus, version):
    # coupled-tanks: one switch, sign(e_tank1 - e_tank2) of the orifice between the tanks,
    # e_tank_i = rho g V_i / A_i (hydraulic C, Karnopp et al. ch. 4)
    p = library.build("coupled-tanks").equations().param_values
    m = Model(fmus("coupled-tanks", version))
    try:
        assert m.nz == 1
        m.start()
        for volumes in ((0.003, 0.001), (0.001, 0.003)):
            x = np.array([volumes[m.state_names.index(n)] for n in ("V1", "V2")])
            m.set_x(x)
            v = dict(zip(m.state_names, x))
            expected = p["rho"] * p["g_acc"] * (v["V1"] / p["A1"] - v["V2"] / p["A2"])
            assert m.z()[0] == pytest.approx(expected, rel=1e-14)
    finally:
        m.close()
