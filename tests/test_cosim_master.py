"""The co-simulation master, Python blocks and FMUComponent, against independent references."""
from __future__ import annotations

import math

import numpy as np
import pytest
from fmpy.validation import validate_fmu
from scipy.linalg import expm

from cosim import (PI, CoSimulation, Constant, CosimResult, FMUComponent, Function, PythonBlock,
                   Step, Table)
from cosim_helpers import handwritten_msd


@pytest.fixture(scope="session")
def msd_fmu(tmp_path_factory):
    return handwritten_msd(tmp_path_factory)


class Delay(PythonBlock):
    """One-step delay: y_k = u_{k-1} (no feedthrough)."""

    def __init__(self, name):
        super().__init__(name, inputs=["u"], outputs=["y"], feedthrough=())
        self.held = 0.0

    def start(self, t0):
        self.held = 0.0

    def output(self, t):
        self.y[0] = self.held

    def advance(self, t, dt):
        self.held = float(self.u[0])


class TwoChannels(PythonBlock):
    """y1 = u1, y2 = u2, each feeding through on its own."""

    def __init__(self, name):
        super().__init__(name, inputs=["u1", "u2"], outputs=["y1", "y2"],
                         feedthrough=[("u1", "y1"), ("u2", "y2")])

    def output(self, t):
        self.y[:] = self.u


def test_handwritten_fmu_validates_and_exposes_ports_units_and_feedthrough(msd_fmu, tmp_path_factory):
    assert validate_fmu(str(msd_fmu)) == []
    plant = FMUComponent(msd_fmu, name="msd")
    assert [(p.name, p.unit) for p in plant.inputs] == [("F", "N")]
    assert [(p.name, p.unit) for p in plant.outputs] == [("x", "m"), ("v", "m/s")]
    assert plant.feedthrough == frozenset()          # dependencies="" declared
    # without dependencies attributes an output depends on every input (FMI 2.0, 3.0)
    loose = FMUComponent(handwritten_msd(tmp_path_factory, declare_dependencies=False))
    assert validate_fmu(str(loose.path)) == []
    assert loose.feedthrough == {("F", "x"), ("F", "v")}
    assert FMUComponent(msd_fmu, feedthrough=[("F", "v")]).feedthrough == {("F", "v")}


def _sampled_loop_reference(m, k, c, x0, dt, n, r_of_t, kp, ki, u_min, u_max):
    """Monolithic reference: exact zero-order-hold plant (matrix exponential) and the
    PI law of cosim.PI's docstring, written out by hand."""
    a = np.array([[0.0, 1.0], [-k / m, -c / m]])
    b = np.array([0.0, 1.0 / m])
    # exp([[A, B], [0, 0]] dt) = [[Ad, Bd], [0, 1]]: exact discretisation with F held
    big = expm(np.block([[a, b[:, None]], [np.zeros((1, 3))]]) * dt)
    ad, bd = big[:2, :2], big[:2, 2]
    state, integral = np.array([x0, 0.0]), 0.0
    xs, vs, us = [], [], []
    for j in range(n + 1):
        e = r_of_t(j * dt) - state[0]
        v = kp * e + ki * integral
        u = min(max(v, u_min), u_max)
        xs.append(state[0]), vs.append(state[1]), us.append(u)
        if not ((v > u_max and e > 0) or (v < u_min and e < 0)):
            integral += dt * e
        state = ad @ state + bd * u
    return np.array(xs), np.array(vs), np.array(us)


def test_fmu_with_pi_controller_equals_monolithic_sampled_loop(msd_fmu):
    m, k, c, x0, dt, n = 2.0, 50.0, 3.0, 0.02, 1e-3, 1500
    kp, ki, u_max = 150.0, 300.0, 10.0
    plant = FMUComponent(msd_fmu, name="plant", parameters={"m": m, "k": k, "c": c},
                         start_values={"x0": x0})
    pi = PI("pi", kp=kp, ki=ki, u_min=-u_max, u_max=u_max, unit_in="m", unit_out="N")
    ref = Step("ref", 0.05, before=0.02, after=0.1, unit="m")
    sim = CoSimulation([plant, pi, ref],
                       [("ref.y", "pi.r"), ("plant.x", "pi.y_m"), ("pi.u", "plant.F")], step=dt)
    result = sim.run(n * dt)
    xs, vs, us = _sampled_loop_reference(m, k, c, x0, dt, n, lambda t: 0.02 if t < 0.05 else 0.1,
                                         kp, ki, -u_max, u_max)
    # the FMU's RK4 (0.1 ms sub-steps) against the exact solution: ~1e-14 relative here
    for name, want in (("plant.x", xs), ("plant.v", vs), ("pi.u", us), ("plant.F", us)):
        err = np.max(np.abs(result[name] - want)) / np.max(np.abs(want))
        assert err < 1e-10, (name, err)
    assert np.sum(us == u_max) > 10                 # the limit and anti-windup were exercised
    assert result.units["plant.x"] == "m" and result.units["pi.u"] == "N"
    assert result.kinds["plant.x"] == "output" and result.kinds["plant.F"] == "input"
    assert result.info["n_steps"] == n and result.info["step"] == dt
    assert result.t[-1] == pytest.approx(1.5, abs=1e-15)


def test_python_blocks_chain_matches_hand_computation():
    dt, n, kp, ki = 0.03, 40, 2.0, 5.0
    table = Table("table", [0.0, 0.3, 0.6], [1.0, -1.0, 0.5], "m", interpolation="hold")
    meas = Function("meas", lambda t: 0.2 * math.sin(3.0 * t), "m")
    pi = PI("pi", kp=kp, ki=ki, unit_in="m")
    ramp = Table("ramp", [0.0, 1.2], [0.0, 2.4])
    step = Step("step", 0.33, before=1.0, after=3.0)
    gain = Constant("c", 4.5)
    sim = CoSimulation([pi, table, meas, ramp, step, gain],
                       [("table.y", "pi.r"), ("meas.y", "pi.y_m")], step=dt)
    r = sim.run(n * dt)
    t = dt * np.arange(n + 1)
    # hand computation: zero-order hold of the table on the grid, then the PI recurrence
    kk = np.arange(n + 1)                       # breakpoints 0.3 s, 0.6 s are k = 10, 20
    setpoint = np.where(kk < 10, 1.0, np.where(kk < 20, -1.0, 0.5))
    e = setpoint - 0.2 * np.sin(3.0 * t)
    integral = np.concatenate([[0.0], dt * np.cumsum(e)[:-1]])
    np.testing.assert_allclose(r["pi.r"], setpoint, rtol=0, atol=0)
    np.testing.assert_allclose(r["pi.u"], kp * e + ki * integral, rtol=1e-13, atol=1e-13)
    np.testing.assert_allclose(r["ramp.y"], 2.0 * t, rtol=1e-13, atol=1e-15)
    # 11 * 0.03 = 0.32999999999999996 < 0.33: the step still switches at k = 11
    assert r["step.y"][10] == 1.0 and r["step.y"][11] == 3.0 and np.all(r["c.y"] == 4.5)


def test_feedthrough_chain_has_no_delay_and_a_delay_block_one_step():
    blocks = [PI("pi2", kp=2.0, ki=0.0), PI("pi1", kp=2.0, ki=0.0), Step("s", 0.2),
              Delay("d"), Constant("zero", 0.0)]
    wires = [("s.y", "pi1.r"), ("pi1.u", "pi2.r"), ("zero.y", "pi1.y_m"),
             ("zero.y", "pi2.y_m"), ("pi2.u", "d.u")]
    sim = CoSimulation(blocks, wires, step=0.1)
    assert sim.order.index("s") < sim.order.index("pi1") < sim.order.index("pi2")
    r = sim.run(0.5)
    np.testing.assert_array_equal(r["s.y"], [0, 0, 1, 1, 1, 1])
    np.testing.assert_array_equal(r["pi2.u"], [0, 0, 4, 4, 4, 4])   # same instant
    np.testing.assert_array_equal(r["d.y"], [0, 0, 0, 4, 4, 4])      # one step later


def test_component_cycle_without_port_loop_is_exact_in_repeated_passes():
    # a.y1 -> b.u1 -> b.y1 -> a.u2 -> a.y2 -> b.u2 -> b.y2: a cycle of components, not of ports
    a, b = TwoChannels("a"), TwoChannels("b")
    sim = CoSimulation([b, a, Step("s", 0.1, after=2.0)],
                       [("s.y", "a.u1"), ("a.y1", "b.u1"), ("b.y1", "a.u2"), ("a.y2", "b.u2")],
                       step=0.1)
    assert sim.order == ("s", "b", "a", "b", "a", "b", "a")   # 3 passes for b-first order
    r = sim.run(0.3)
    for name in ("a.y1", "b.y1", "a.y2", "b.y2"):
        np.testing.assert_array_equal(r[name], [0, 2, 2, 2])


def test_unconnected_input_keeps_its_start_value():
    pi = PI("pi", kp=1.0, ki=0.0)
    r = CoSimulation([pi, Constant("r", 3.0)], [("r.y", "pi.r")], step=0.5).run(1.0)
    np.testing.assert_array_equal(r["pi.y_m"], [0.0, 0.0, 0.0])
    np.testing.assert_array_equal(r["pi.u"], [3.0, 3.0, 3.0])


def test_result_csv_round_trip_and_plot(tmp_path, msd_fmu):
    plant = FMUComponent(msd_fmu, name="plant", parameters={"x0": 0.01})
    sim = CoSimulation([plant, Function("f", lambda t: math.cos(7 * t), "N")],
                       [("f.y", "plant.F")], step=0.01)
    result = sim.run(0.5)
    path = tmp_path / "cosim.csv"
    result.to_csv(path)
    assert path.read_text().splitlines()[0] == "time [s],plant.x [m],plant.v [m/s],f.y [N],plant.F [N]"
    back = CosimResult.from_csv(path)
    assert back.names == result.names and dict(back.units) == dict(result.units)
    np.testing.assert_array_equal(back.t, result.t)
    for name in result.names:
        np.testing.assert_array_equal(back[name], result[name])
    fig = result.plot()
    assert type(fig).__module__ == "matplotlib.figure" and len(fig.axes) == 3   # m, m/s, N
    assert [line.get_label() for line in fig.axes[0].lines] == ["plant.x [m]"]


def test_fmu_state_rollback_and_restart(msd_fmu):
    plant = FMUComponent(msd_fmu, parameters={"x0": 0.05})
    u, y = np.array([1.5]), np.zeros(2)
    plant.bind(u, y)
    plant.start(0.0)
    try:
        for j in range(5):
            plant.advance(j * 0.01, 0.01)
        saved = plant.get_state()
        first = []
        for j in range(5, 10):
            plant.advance(j * 0.01, 0.01)
            plant.output((j + 1) * 0.01)
            first.append(y.copy())
        plant.set_state(saved)
        plant.free_state(saved)
        for j in range(5, 10):
            plant.advance(j * 0.01, 0.01)
            plant.output((j + 1) * 0.01)
            np.testing.assert_array_equal(y, first[j - 5])
    finally:
        plant.stop()
    plant.stop()   # a second stop is harmless
    # the same co-simulation runs twice to the same numbers (each run re-instantiates)
    sim = CoSimulation([plant, Constant("f", 1.0, "N")], [("f.y", "handwritten_msd.F")], step=0.1)
    a, b = sim.run(1.0), sim.run(1.0)
    np.testing.assert_array_equal(a["handwritten_msd.x"], b["handwritten_msd.x"])


def test_progress_bar_only_when_asked(capsys):
    sim = CoSimulation([Constant("c", 1.0)], [], step=0.01)
    sim.run(1.0)
    assert capsys.readouterr().err == ""
    sim.run(1.0, progress=True)
    err = capsys.readouterr().err
    assert "100%" in err and err.endswith("\n")
