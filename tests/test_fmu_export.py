"""FMU export: every exported FMU passes fmpy's validator and simulates in fmpy
(Co-Simulation, and Model Exchange where offered) to :func:`bondgraph.numerics.simulate`'s result."""
from __future__ import annotations

import zipfile

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

import bondgraph as bg
from bondgraph.numerics import simulate
import plants.library as library
from bondgraph.errors import FMUError
from fmus import default_solver_step, export

from fmu_helpers import open_slave

VERSIONS = (2, 3)
TEXTBOOK = ("mass-spring-damper", "dc-motor", "rlc", "coupled-tanks", "geared-inertias",
            "resistor-loop", "resistor-loop-nl", "chain")
#: Non-default constant inputs, so the FMUs do something.
INPUTS = {
    "mass-spring-damper": {"F": 2.0}, "dc-motor": {"V": 12.0, "tau_L": 0.01}, "rlc": {"V": 5.0},
    "coupled-tanks": {"Q_in": 2e-4}, "geared-inertias": {"tau": 1.5}, "resistor-loop": {"V": 3.0},
    "resistor-loop-nl": {"V": 3.0}, "chain": {"F": 1.0}, "exoskeleton": {"tau_m": 0.2, "w_h": 0.5},
    "pam": {"u1": 7.0, "u2": 3.0}, "pam-locked": {"u1": 7.0, "u2": 3.0},
}


@pytest.fixture(scope="session")
def exported(exported_fmu):
    """`exported(model, version)` -> path of the FMU, built once per session."""
    return exported_fmu


def _reference(model, T, dt, inputs):
    return simulate(library.build(model), (0.0, T), output_interval=dt, inputs=inputs)


@pytest.mark.parametrize("version", VERSIONS)
@pytest.mark.parametrize("model", (*TEXTBOOK, "exoskeleton", "pam", "pam-locked"))
def test_exported_fmu_validates_and_matches_the_python_model(exported, model, version):
    path = exported(model, version)
    assert validate_fmu(str(path)) == []
    eqs = library.build(model).equations()
    md = read_model_description(str(path))
    assert (md.modelExchange is not None) == eqs.is_smooth   # held variables: CS only
    T, dt = 1.0, 1e-3
    ref = _reference(model, T, dt, INPUTS[model])
    scale = {o: max(1.0, np.max(np.abs(ref[o]))) for o in eqs.outputs}
    cs = simulate_fmu(str(path), stop_time=T, output_interval=dt, fmi_type="CoSimulation",
                      start_values=INPUTS[model])
    # Fixed-step models run the very same RK4 kernel; smooth ones RK4 vs solve_ivp.
    tol = 1e-12 if not eqs.is_smooth else 1e-6
    for o in eqs.outputs:
        assert np.allclose(cs[o], ref[o], rtol=0, atol=tol * scale[o]), o
    if eqs.is_smooth:
        me = simulate_fmu(str(path), stop_time=T, output_interval=dt, fmi_type="ModelExchange",
                          start_values=INPUTS[model], relative_tolerance=1e-10)
        for o in eqs.outputs:
            assert np.allclose(me[o], ref[o], rtol=0, atol=1e-6 * scale[o]), o


@pytest.mark.parametrize("version", VERSIONS)
def test_pam_follows_a_changing_input_to_rounding(exported, version):
    """Inputs changed at every communication point (zero-order hold), held friction:
    the FMU and bondgraph.numerics.simulate run the same kernel with the same steps (the
    sub-step differs in the last bits: simulate divides grid differences)."""
    dt, n = 1e-3, 2000
    t = np.arange(n + 1) * dt
    u1 = 5.0 + 3.0 * np.sign(np.sin(2 * np.pi * t) + 1e-9)   # 8 V / 2 V, swapped every 0.5 s
    u2 = 10.0 - u1
    ref = simulate(library.build("pam"), (0.0, n * dt), output_interval=dt,
                      inputs={"u1": (t, u1), "u2": (t, u2)})
    with open_slave(exported("pam", version)) as fmu:
        out = []
        for k in range(n):
            fmu.set(["u1", "u2"], [u1[k], u2[k]])
            out.append(fmu.get(["psi", "P1", "tau"]))
            fmu.do_step(t[k], dt)
        out.append(fmu.get(["psi", "P1", "tau"]))
    out = np.array(out)
    assert np.ptp(ref["psi"]) > 10.0                         # the joint swings (deg)
    assert np.allclose(out[:, 0], ref["psi"], rtol=1e-12, atol=1e-12)
    assert np.allclose(out[:, 1], ref["P1"], rtol=1e-12, atol=0)
    assert np.allclose(out[:, 2], ref["tau"], rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("version", VERSIONS)
def test_parameters_and_initial_states_are_settable_before_initialisation(exported, version):
    path = exported("mass-spring-damper", version)
    eqs = library.build("mass-spring-damper").equations()
    p = {n: 2.0 * v for n, v in eqs.param_values.items()}
    x0 = {eqs.state_names[0]: 0.3}
    res = simulate_fmu(str(path), stop_time=1.0, output_interval=1e-3,
                       start_values={**p, **x0, "F": 1.0})
    ref = simulate(library.build("mass-spring-damper"), (0.0, 1.0), output_interval=1e-3,
                      params=p, x0=x0, inputs={"F": 1.0})
    for o in eqs.outputs:
        assert np.allclose(res[o], ref[o], rtol=0, atol=1e-7)


@pytest.mark.parametrize("version", VERSIONS)
def test_fixed_parameters_cannot_change_while_running(exported, version):
    with open_slave(exported("mass-spring-damper", version)) as fmu:
        name = library.build("mass-spring-damper").equations().param_names[0]
        with pytest.raises(FMICallException):
            fmu.set([name], [1.0])
        assert any(f"{name} can only be set before initialisation" in m for m in fmu.messages)


@pytest.mark.parametrize("version", VERSIONS)
def test_fmu_state_rolls_back_and_serialises(exported, version):
    with open_slave(exported("pam", version)) as fmu:
        fmu.set(["u1", "u2"], [8.0, 2.0])
        for k in range(100):
            fmu.do_step(k * 1e-3, 1e-3)
        state = fmu.get_state()
        blob = fmu.serialize(state)

        def run(k0):
            for k in range(k0, k0 + 100):
                fmu.do_step(k * 1e-3, 1e-3)
            return fmu.get(["psi", "P1", "P2", "T_f"])
        first = run(100)
        fmu.set_state(state)
        assert run(100) == first
        fmu.set_state(fmu.deserialize(blob))
        assert run(100) == first
        fmu.free_state(state)


def test_default_solver_step_follows_the_fastest_pole():
    msd = library.build("mass-spring-damper").equations()
    rho = np.max(np.abs(np.linalg.eigvals(np.asarray(msd.linearize().A, dtype=float))))
    h = default_solver_step(msd)
    assert 0.02 / rho <= h <= 0.05 / rho or h == 1e-3
    assert default_solver_step(library.build("pam").equations()) == 2.5e-4   # the model's fixed step


def test_time_functions_are_compiled_into_the_fmu(exported, tmp_path):
    """An input given as a function of t has no FMU input: the function is compiled in."""
    g = bg.BondGraph("driven")
    for element in (bg.Se("F", "2*sin(3*t)", domain="translation"), bg.One("v"),
                    bg.I("m", 1.0, domain="translation"), bg.R("b", 0.5, domain="translation")):
        g.add(element)
    g.connect("F", "v")
    g.connect("v", "m")
    g.connect("v", "b")
    g.add_output("v_m", "f_m", unit="m/s")
    path = export(g, tmp_path / "driven.fmu")
    assert validate_fmu(str(path)) == []
    md = read_model_description(str(path))
    assert [v.name for v in md.modelVariables if v.causality == "input"] == []
    res = simulate_fmu(str(path), stop_time=2.0, output_interval=1e-3)
    t = res["time"]
    # m dv/dt = 2 sin 3t - b v, v(0) = 0: v = A (b sin 3t - 3 m cos 3t + 3 m e^{-b t/m}) / (b^2 + 9 m^2)
    exact = 2.0 * (0.5 * np.sin(3 * t) - 3 * np.cos(3 * t) + 3 * np.exp(-0.5 * t)) / (0.25 + 9)
    assert np.allclose(res["v_m"], exact, rtol=0, atol=1e-9)


def test_export_rejects_bad_arguments(tmp_path):
    msd = library.build("mass-spring-damper")
    with pytest.raises(FMUError, match="fmi_version"):
        export(msd, tmp_path / "a.fmu", fmi_version=4)
    with pytest.raises(FMUError, match="no parameter.*nope"):
        export(msd, tmp_path / "a.fmu", params={"nope": 1.0})
    with pytest.raises(FMUError, match="solver_step"):
        export(msd, tmp_path / "a.fmu", solver_step=-1.0)
    with pytest.raises(TypeError, match="BondGraph or StateEquations"):
        export("mass-spring-damper", tmp_path / "a.fmu")


def test_exported_file_is_reproducible_and_minimal(exported, tmp_path):
    a = exported("rlc", 2)
    b = export(library.build("rlc"), tmp_path / "rlc.fmu")
    assert a.read_bytes() == b.read_bytes()
    with zipfile.ZipFile(a) as z:
        assert sorted(z.namelist()) == [
            "binaries/linux64/rlc_series.so", "modelDescription.xml", "sources/bc_adaptive.h",
            "sources/bc_fmu_core.h", "sources/bc_partials.h",
            "sources/bc_platform.h", "sources/fmi2FunctionTypes.h", "sources/fmi2Functions.h",
            "sources/fmi2TypesPlatform.h", "sources/fmi2_wrapper.c", "sources/model.h",
            "sources/model_kernels.c"]


@pytest.mark.parametrize("version", VERSIONS)
def test_setting_an_output_is_refused_with_its_name(exported, version):
    with open_slave(exported("rlc", version)) as fmu:
        with pytest.raises(FMICallException):
            fmu.set(["v_C"], [1.0])
        assert any("v_C is calculated by the FMU" in m for m in fmu.messages), fmu.messages


@pytest.mark.parametrize("version", VERSIONS)
@pytest.mark.parametrize("model", library.names())
def test_every_builtin_model_validates_with_its_partials_declared(exported, model, version):
    path = exported(model, version)
    assert validate_fmu(str(path)) == []
    eqs = library.build(model).equations()
    md = read_model_description(str(path))
    with zipfile.ZipFile(path) as z:
        xml = z.read("modelDescription.xml").decode()
    # every library law has a symbolic derivative: both interfaces declare directional derivatives
    flag = "providesDirectionalDerivative" + ("" if version == 2 else "s") + '="true"'
    assert xml.count(flag) == (2 if eqs.is_smooth else 1)
    if not eqs.is_smooth:
        assert md.numberOfEventIndicators == 0


def test_export_is_the_function_and_exporter_the_module():
    # the module used to be fmus/export.py: importing it rebound fmus.export to the module
    import importlib

    import fmus
    import fmus.exporter
    module = importlib.import_module("fmus.exporter")
    assert fmus.export is module.export and callable(fmus.export)
    with pytest.raises(ModuleNotFoundError):
        importlib.import_module("fmus.export")


def test_a_stiff_model_steps_at_its_stability_limit_not_below():
    """The exoskeleton's fastest modes are well damped: RK4 at 1 / rho(A) (1e-5 s), not 0.05 / rho."""
    assert default_solver_step(library.build("exoskeleton").equations()) == 1e-5
    assert default_solver_step(library.build("dc-motor").equations()) == 2e-5     # accuracy rule, not stiff


@pytest.mark.parametrize("version", VERSIONS)
def test_a_model_with_a_sensor_lag_exports_its_signal_state(tmp_path, version):
    """The diagnosis's improved model may read an output through a sensor's own state (an
    equation element without ports, ``sense_output``): the FMU validates and, co-simulated and
    model-exchanged, gives the Python model's lagged position."""
    import sympy as sp

    from bondgraph import Param
    g = library.build("mass-spring-damper")
    y_s, tau = sp.Symbol("y_s"), sp.Symbol("tau_x")
    lag = g.sense_output("x", {"y_s": lambda y: (y - y_s) / tau}, y_s, initial={"y_s": 0.0},
                         units={"y_s": "m"}).declare(Param("tau_x", 0.2, "s", "time constant of the x sensor"))
    path = export(lag, tmp_path / f"lagged_v{version}.fmu", fmi_version=version)
    assert validate_fmu(str(path)) == []
    T, dt = 2.0, 1e-3
    ref = simulate(lag, (0.0, T), output_interval=dt, inputs={"F": 1.0})
    assert np.ptp(ref["x"]) > 0.05
    for kind in ("CoSimulation", "ModelExchange"):
        res = simulate_fmu(str(path), stop_time=T, output_interval=dt, fmi_type=kind, start_values={"F": 1.0},
                           relative_tolerance=1e-10)
        assert np.allclose(res["x"], ref["x"], rtol=0, atol=1e-6), kind
