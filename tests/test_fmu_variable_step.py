"""The variable-step Co-Simulation solver inside exported FMUs (issue 12, part 3):
Dormand-Prince 5(4) with error control (``solver = 1``, ``tolerance``), against the analytic
mass-spring-damper response, bondgraph.numerics.simulate (LSODA) on an algebraic-loop model, and the
singularity of the vented frictionless PAM; fixed-step models refuse it."""
from __future__ import annotations

import math

import pytest
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

from bondgraph.numerics import simulate
import plants.library as library

from fmu_helpers import Slave, open_slave

VERSIONS = (2, 3)


@pytest.fixture(scope="module")
def fmu(exported_fmu):
    def get(model, version):
        path = exported_fmu(model, version)
        assert validate_fmu(str(path)) == []
        return path
    return get


def _msd_exact(t, F=2.0, m=1.0, b=0.4, k=4.0):
    """Step response of m x'' + b x' + k x = F from rest (underdamped), m."""
    wn, zeta = math.sqrt(k / m), b / (2 * math.sqrt(k * m))
    wd = wn * math.sqrt(1 - zeta ** 2)
    return F / k * (1 - math.exp(-zeta * wn * t) * (math.cos(wd * t) + zeta * wn / wd * math.sin(wd * t)))


def _run_msd(path, H, n, **start):
    with open_slave(path, {"F": 2.0, **start}) as s:
        t = 0.0
        for _ in range(n):
            s.do_step(t, H)
            t += H
        return s.get(["q_k"])[0], t


@pytest.mark.parametrize("version", VERSIONS)
def test_long_steps_with_error_control_match_the_analytic_response(fmu, version):
    path = fmu("mass-spring-damper", version)
    # 1 s communication steps with at most 100 internal steps each: fixed-step RK4 at the
    # default 1 ms would need 1000 and is discarded; Dormand-Prince needs a few dozen
    with open_slave(path, {"F": 2.0, "max_substeps": 100.0}) as s:
        with pytest.raises(FMICallException) as info:
            s.do_step(0.0, 1.0)
        assert info.value.status == 2
    errors = []
    for tol in (1e-6, 1e-8, 1e-10):
        x, t = _run_msd(path, 1.0, 10, solver=1.0, tolerance=tol, max_substeps=100.0)
        errors.append(abs(x - _msd_exact(t)))
    assert errors[0] < 1e-5 and errors[1] < 1e-7 and errors[2] < 1e-9
    assert errors[2] < errors[1] < errors[0]     # tighter tolerance, smaller error


@pytest.mark.parametrize("version", VERSIONS)
def test_algebraic_loop_model_matches_simulate(fmu, version):
    eqs = library.build("resistor-loop-nl").equations()
    names = list(eqs.outputs) + list(eqs.state_names)
    ref = simulate(eqs, (0.0, 1.0), inputs={"V": 3.0}, output_interval=0.1)
    with open_slave(fmu("resistor-loop-nl", version), {"V": 3.0, "solver": 1.0}) as s:
        t = 0.0
        for k in range(10):
            s.do_step(t, 0.1)
            t = round(t + 0.1, 12)
            got = s.get(names)
            for name, value in zip(names, got):
                assert value == pytest.approx(ref[name][k + 1], rel=1e-6), (name, t)


@pytest.mark.parametrize("version", VERSIONS)
def test_singularity_is_discarded_where_lsoda_stops(fmu, version):
    # muscle 2's volume vanishes at t = 0.02452 s (simulate's LSODA gives up at 0.0245203 s)
    with open_slave(fmu("pam-frictionless", version), {"solver": 1.0}) as s:
        t = 0.0
        with pytest.raises(FMICallException) as info:
            while t < 1.0:
                s.do_step(t, 1e-3)
                t = round(t + 1e-3, 12)
        assert info.value.status == 2 and t == pytest.approx(0.024)
        msg = s.messages[-1]
    assert "underflows" in msg and "V_2 = " in msg
    t_sing = float(msg.split("at t = ")[1].split()[0])
    assert t_sing == pytest.approx(0.0245203, abs=1e-6)


@pytest.mark.parametrize("version", VERSIONS)
def test_fixed_step_models_refuse_the_variable_step_solver(fmu, version):
    s = Slave(fmu("pam", version))
    try:
        with pytest.raises(FMICallException):
            s.set(["solver"], [1.0])
        assert "held variables need the fixed step" in s.messages[-1]
    finally:
        s.close()
