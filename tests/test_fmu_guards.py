"""A step never lies: the cases measured in issue 12 (overflowing sub-step counts, unbounded
doSteps, leaving the physical domain, NaN inputs, negative masses), driven through fmpy
(FMI 2.0 and 3.0), through ``bondgraph.numerics.simulate`` and through the co-simulation master."""
from __future__ import annotations

import math

import pytest
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

import bondgraph as bg
from bondgraph.numerics import simulate
import plants.library as library
from bondgraph.errors import DomainError, FMUStepDiscarded, ParameterError, SimulationError
from bondgraph.guards import Guard
from bondgraph.io_json import graph_from_dict, graph_to_dict
from fmus import export

from fmu_helpers import Slave, open_slave

VERSIONS = (2, 3)
DISCARD = 2   # fmi2Discard == fmi3Discard


@pytest.fixture(scope="module")
def fmu(exported_fmu):
    def get(model, version, **kwargs):
        path = exported_fmu(model, version, **kwargs)
        assert validate_fmu(str(path)) == []
        return path
    return get


def _discarded(slave, t, h):
    with pytest.raises(FMICallException) as info:
        slave.do_step(t, h)
    assert info.value.status == DISCARD
    return slave.messages[-1]


@pytest.mark.parametrize("version", VERSIONS)
def test_huge_communication_step_is_discarded_not_overflowed(fmu, version):
    # issue 12: H = 1e7 s gave x = -1.6e27 with fmi2OK ((int)ceil overflow), 1e6 s blocked 54 s
    path = fmu("mass-spring-damper", version)
    with open_slave(path, {"F": 2.0}) as s:
        before = s.get(["p_m", "q_k"])
        for H in (1e7, 1e6):
            msg = _discarded(s, 0.0, H)
            assert "max_substeps" in msg and f"H = {H:g} s" in msg
            assert s.get(["p_m", "q_k"]) == before   # left at the step's start
        s.do_step(0.0, 0.5)   # and it goes on normally
        m, k, b = (library.build("mass-spring-damper").equations().param_values[n] for n in "mkb")
        x = s.get(["q_k"])[0]
        # analytic step response of m x'' + b x' + k x = F from rest (underdamped)
        wn, zeta = math.sqrt(k / m), b / (2 * math.sqrt(k * m))
        wd = wn * math.sqrt(1 - zeta ** 2)
        ref = 2.0 / k * (1 - math.exp(-zeta * wn * 0.5) * (math.cos(wd * 0.5)
                                                         + zeta * wn / wd * math.sin(wd * 0.5)))
        assert x == pytest.approx(ref, rel=1e-7)


@pytest.mark.parametrize("version", VERSIONS)
def test_tiny_solver_step_is_discarded(fmu, version):
    # issue 12: solver_step = 1e-13 on dc-motor gave i = -64360 A with fmi2OK
    path = fmu("dc-motor", version, solver_step=1e-13)
    with open_slave(path, {"V": 12.0}) as s:
        msg = _discarded(s, 0.0, 1e-3)
        assert "1e+10 sub-steps" in msg and "solver_step = 1e-13 s" in msg
        assert s.get(list(library.build("dc-motor").equations().state_names)) == [0.0, 0.0]


@pytest.mark.parametrize("version", VERSIONS)
def test_max_substeps_is_a_parameter(fmu, version):
    path = fmu("mass-spring-damper", version)
    with open_slave(path, {"max_substeps": 10.0, "solver_step": 1e-3}) as s:
        _discarded(s, 0.0, 0.011)   # 11 sub-steps
        s.do_step(0.0, 0.01)        # 10 are allowed
    with pytest.raises(FMICallException):
        with open_slave(path, {"max_substeps": 0.5}):
            pass


@pytest.fixture(scope="module")
def t_singular():
    """Where the vented frictionless PAM's chamber 2 vanishes: bondgraph.numerics.simulate's adaptive
    solvers (LSODA, DOP853 at rtol 1e-10) grind to a halt at t = 0.0245203 s, where muscle 2's
    chamber volume V_2 -> 0 and P_2 -> infinity.  DOP853 is there after 20 000 evaluations (to 1e-10 s
    of where it stops after the default 500 000, a minute's work)."""
    with pytest.raises(SimulationError) as info:
        simulate(library.build("pam-frictionless"), (0, 0.1), method="DOP853", output_interval=1e-3,
                 rtol=1e-10, atol=1e-8, max_nfev=20_000)
    return info.value.time


@pytest.mark.parametrize("version", VERSIONS)
def test_vented_frictionless_pam_is_discarded_when_a_chamber_volume_vanishes(fmu, version, t_singular):
    # issue 12: pam-frictionless from vented muscles reached psi = 142 deg, P2 = 2.08e6 Pa, fmi2OK.
    assert t_singular == pytest.approx(0.0245203, abs=1e-6)
    path = fmu("pam-frictionless", version)
    h = 1e-3
    with open_slave(path) as s:
        step = s.get(["solver_step"])[0]
        t, last = 0.0, None
        while t < 1.0:
            try:
                s.do_step(t, h)
            except FMICallException as exc:
                assert exc.status == DISCARD
                break
            last = s.get(["q_psi", "P_2", "psi"])
            t = round(t + h, 12)
        msg = s.messages[-1]
        assert s.get(["q_psi", "P_2", "psi"]) == last   # still at the start of the failed step
    # The RK4 sub-step (solver_step = 0.5 ms) containing the singularity is refused: a stage
    # state there has V_2 < 0.  (Before the stages were checked, the sub-step jumped across
    # the singularity, landed with V_2 > 0 and P_2 = 5.1e6 Pa, and the FMU swung on until
    # muscle 1's volume vanished at 34 ms.)
    assert "V_2 = -" in msg and "muscle2" in msg and "RK4 stage" in msg
    t_stage = float(msg.split("RK4 stage at t = ", 1)[1].split()[0])
    t_sub = float(msg.split("sub-step from t = ", 1)[1].split()[0])
    assert t_sub <= t_singular < t_sub + step and t_sub < t_stage <= t_sub + step
    assert t == pytest.approx(0.024) and last[1] < 7.1e5   # P_2 below the supply pressure


@pytest.mark.parametrize("version", VERSIONS)
def test_initial_state_outside_the_domain_is_an_error_naming_the_guard(fmu, version):
    # issue 12: pam at psi = 0.7 rad gave an absolute pressure of -1.1e5 Pa
    path = fmu("pam", version)
    s = Slave(path)
    try:
        with pytest.raises(FMICallException):
            s.start({"q_psi": 0.7})
        assert "V_2 = -6.09" in s.messages[-1] and "m^3" in s.messages[-1]
    finally:
        s.close()


@pytest.mark.parametrize("version", VERSIONS)
def test_nan_input_and_out_of_range_parameter_are_rejected(fmu, version):
    pam_path = fmu("pam-locked", version)
    with open_slave(pam_path, {"u1": 5.0}) as s:
        with pytest.raises(FMICallException) as info:
            s.set(["u1"], [float("nan")])
        assert info.value.status == 3   # Error, and nothing is set
        assert "u1 = nan rejected" in s.messages[-1]
        assert s.get(["u1"]) == [5.0]
    msd = fmu("mass-spring-damper", version)
    s = Slave(msd)
    try:
        with pytest.raises(FMICallException):
            s.set(["m"], [-1.0])
        assert "m = -1 rejected: outside its declared range [0, inf]" in s.messages[-1]
        s.set(["m"], [2.0])
        assert s.get(["m"]) == [2.0]
    finally:
        s.close()


def test_simulate_guards_and_bounds():
    with pytest.raises(ParameterError, match=r"'m' = -1.0 kg is outside its physical range"):
        simulate(library.build("mass-spring-damper"), (0, 1), params={"m": -1.0})
    # eq. (3) with Table II at psi = 0.7 rad: l2 = L0 + r sin(psi), V2 = D1 l2^2 + D2 l2 + D3
    l2 = 0.165 + 0.0365 * math.sin(0.7)
    v2 = -2.440e-2 * l2 ** 2 + 6.824e-3 * l2 - 4.254e-4
    with pytest.raises(DomainError) as info:
        simulate(library.build("pam-frictionless"), (0, 0.01), x0={"q_psi": 0.7})
    assert info.value.variable == "V_2" and info.value.time == 0.0
    assert info.value.value == pytest.approx(v2, rel=1e-12) and v2 < 0
    with pytest.raises(ParameterError, match=r"'m' = -1.0 kg is outside its physical range"):
        bg.I("m", -1.0, domain="translation")


def test_graph_guard_on_a_smooth_model_stops_at_the_crossing():
    # x'' = -k/m x from x(0) = 0.1 m: x = 0.1 cos(w t) reaches 0 at t = pi / (2 w)
    g = library.build("mass-spring-damper")
    g.add_guard(Guard("x_pos", "q_k", min=0.0, unit="m", description="spring extension"))
    eqs = g.equations()
    m, k = eqs.param_values["m"], eqs.param_values["k"]
    with pytest.raises(DomainError) as info:
        simulate(eqs, (0, 10), x0={"q_k": 0.1}, params={"b": 0.0}, inputs={"F": 0.0})
    assert info.value.variable == "x_pos" and info.value.owner == "graph"
    assert info.value.time == pytest.approx(math.pi / 2 / math.sqrt(k / m), rel=1e-6)
    loaded = graph_from_dict(graph_to_dict(g))   # graph and element guards survive JSON
    assert [x.name for x in loaded.equations().guards] == ["x_pos"]
    pam = graph_from_dict(graph_to_dict(library.build("pam")))
    assert [x.name for x in pam.equations().guards] == ["V_1", "P_1_abs", "V_2", "P_2_abs"]
    assert pam.equations().guards[0].expr == library.build("pam").equations().guards[0].expr


def test_cosim_master_reports_a_discard_with_component_and_time(tmp_path):
    from cosim import CoSimulation, FMUComponent
    path = export(library.build("pam-frictionless"), tmp_path / "pf.fmu")
    sim = CoSimulation([FMUComponent(path, "plant")], [], step=1e-3)
    with pytest.raises(FMUStepDiscarded) as info:
        sim.run(1.0)
    exc = info.value
    assert exc.component == "plant" and 0.01 < exc.time < 0.05 and exc.step == 1e-3
    assert "chamber volume of muscle" in exc.reason and "discarded the step" in str(exc)
