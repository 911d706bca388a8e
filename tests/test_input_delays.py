"""Delayed inputs (bondgraph.editing_delays, bondgraph.numerics.input_delays): a graph whose elements
read an input late is simulated exactly on the recorded samples, saved and loaded, refused where
it is wrong, and exported to an FMU as Pade states."""
from __future__ import annotations

import numpy as np
import pytest
from fmpy import simulate_fmu
from fmpy.validation import validate_fmu

from bondgraph.io_json import load, save
import plants.library as library
from bondgraph.errors import ArgumentError, DerivationError, GraphError, ParameterError
from bondgraph.params import Param
from bondgraph.numerics import simulate
from bondgraph.numerics.input_delays import delayed_samples
from diagnosis.recording import Experiment
from diagnosis.residuals import OutputSimulator
from fmus import export

DT = 0.01
T = np.arange(0.0, 4.0 + DT / 2, DT)
#: a force switched on at 0.5 s and reversed at 2 s, the record a zero-order hold
F = np.where(T < 0.5, 0.0, np.where(T < 2.0, 1.0, -0.5))


@pytest.fixture
def msd():
    return library.build("mass-spring-damper")


def test_a_whole_sample_delay_is_the_record_shifted(msd):
    late = msd.delay_input("F", "T_F", 0.25)
    k = 25
    for method in ("RK4", "auto"):
        now = simulate(msd, (0.0, T[-1]), inputs={"F": (T, F)}, output_interval=DT, method=method)
        then = simulate(late, (0.0, T[-1]), inputs={"F": (T, F)}, output_interval=DT, method=method)
        # the same RK4 steps on the same held values: to rounding; solve_ivp within its tolerance
        tol = 1e-12 if method == "RK4" else 1e-7
        assert np.abs(then["x"][k:] - now["x"][:-k]).max() < tol
        assert np.all(then["x"][:k + 1] == 0.0)            # nothing arrives before 0.5 + 0.25 s


def test_a_function_of_time_arrives_late_and_before_it_the_given_value(msd):
    late = msd.delay_input("F", "T_F", 0.1, before=0.0)
    then = simulate(late, (0.0, 3.0), inputs={"F": "cos(2*t)"}, output_interval=DT, method="RK4", dt=1e-3)
    # the force cos(2 (t - 0.1)) from t = 0.1 s, 0 before: the undelayed model on that force
    shifted = simulate(msd, (0.0, 3.0), inputs={"F": "Piecewise((0, t < 0.1), (cos(2*(t - 0.1)), True))"},
                       output_interval=DT, method="RK4", dt=1e-3)
    assert np.abs(then["x"] - shifted["x"]).max() < 1e-9


def test_diagnosis_simulator_delays_each_run_of_a_batch_by_its_own_delay(msd):
    late = msd.delay_input("F", "T_F", 0.0)
    exp = Experiment(T, {"F": F}, {"x": np.zeros_like(T)}, {"F": "N", "x": "m"})
    sim = OutputSimulator(late, exp)
    delays = (0.0, 0.3, 0.053, 0.0049)                # s: none, 30 samples, 5.3 and 0.49 samples
    runs = sim.run_batch([{"T_F": d} for d in delays])
    nominal = OutputSimulator(msd, exp)()["x"]
    assert np.abs(runs[0].outputs["x"] - nominal).max() < 1e-15
    assert np.abs(runs[1].outputs["x"][30:] - nominal[:-30]).max() < 1e-12
    # a fraction of a sample: the force steps inside the intervals, as the adaptive solver of
    # bondgraph.numerics.simulate sees it (its steps cut at the moved breakpoints, rtol 1e-11)
    for d, run in zip(delays, runs):
        ref = simulate(late, (0.0, T[-1]), inputs={"F": (T, F)}, params={"T_F": d}, output_interval=DT,
                       rtol=1e-11, atol=1e-13)
        assert np.abs(run.outputs["x"] - ref["x"]).max() < 1e-8
    # at the samples themselves a zero-order hold reads the value before a step inside the interval
    assert delayed_samples(T, F, 0.005)[50:52].tolist() == [0.0, 1.0]


def test_saved_and_loaded_the_delay_is_still_there(msd, tmp_path):
    late = msd.delay_input("F", "T_F", 0.2, before=-1.0)
    path = tmp_path / "late.json"
    save(late, path)
    again = load(path).equations()
    assert again.input_delays == late.equations().input_delays
    assert again.input_delays["F_late"].before == -1.0 and again.param_values["T_F"] == 0.2


def test_wrong_delays_are_refused_with_their_names(msd):
    with pytest.raises(GraphError, match="delay_of .* and delay"):
        msd.copy().add_input("G", delay_of="F")
    g = msd.copy()
    g.add_input("G", delay_of="Fx", delay="T_F")
    with pytest.raises(DerivationError, match="'Fx'.*its inputs are F"):
        g.equations()
    g = msd.copy()
    g.add_input("G", delay_of="F", delay="T_missing")
    with pytest.raises(DerivationError, match="'T_missing' is not a parameter"):
        g.equations()
    late = msd.delay_input("F", "T_F", 0.2)
    with pytest.raises(GraphError, match="already input 'F' delayed"):
        late.delay_input("F_late", "T_2", 0.1)
    with pytest.raises(ArgumentError, match="'F_late' .* is input 'F' delayed"):
        simulate(late, (0.0, 1.0), inputs={"F_late": 1.0})
    with pytest.raises(ParameterError, match="T_F"):                  # declared with min 0
        simulate(late, (0.0, 1.0), params={"T_F": -0.1})
    g = msd.copy()
    g.add_parameter(Param("T_free", -0.1, "s"))
    g.add_input("G", delay_of="F", delay="T_free")
    with pytest.raises(ArgumentError, match="'T_free' is -0.1 s"):
        simulate(g, (0.0, 1.0))


def test_an_exported_delay_is_pade_states_and_follows_the_exact_delay(msd, tmp_path):
    late = msd.delay_input("F", "T_F", 0.2, before=0.0)   # Pade states start at rest at 0 N
    path = export(late, tmp_path / "late.fmu")
    assert validate_fmu(str(path)) == []
    # steps for fmpy: a time given twice (before and after the step)
    signal = np.array([(0.0, 0.0), (0.5, 0.0), (0.5, 1.0), (2.0, 1.0), (2.0, -0.5), (4.0, -0.5)],
                      dtype=[("time", float), ("F", float)])
    out = simulate_fmu(str(path), stop_time=4.0, output_interval=DT, input=signal)
    exact = simulate(late, (0.0, 4.0), inputs={"F": ([0.0, 0.5, 2.0], [0.0, 1.0, -0.5])}, output_interval=DT)
    # Pade [2/3]: error O((sT)^6); the mass-spring (w_n = 2 rad/s) sees the steps smoothed
    assert np.abs(out["x"] - np.interp(out["time"], exact.t, exact["x"])).max() < 1e-3 * np.ptp(exact["x"])


def test_a_parameter_holds_the_value_before_the_record_and_moves_it(msd, tmp_path):
    # a force held at 1 N from the start, delayed 0.5 s: before the record it rested at F0 (a
    # parameter); a constant force F0 then 1 N from 0.5 s is the undelayed model on that table
    on = np.ones_like(T)
    late = msd.delay_input("F", "T_F", 0.5, before=Param("F0", -2.0, unit="N"))
    assert late.equations().input_delays["F_late"].before == "F0"
    for F0 in (-2.0, 0.0, 3.0):
        then = simulate(late, (0.0, T[-1]), inputs={"F": (T, on)}, params={"F0": F0}, output_interval=DT,
                        method="RK4")
        step = np.where(T < 0.5, F0, 1.0)
        ref = simulate(msd, (0.0, T[-1]), inputs={"F": (T, step)}, output_interval=DT, method="RK4")
        assert np.abs(then["x"] - ref["x"]).max() < 1e-12
        assert then["x"][40] * F0 > 0 or F0 == 0.0                 # the value before moved the mass
    # a batch of the diagnosis simulator: each run its own value before the record
    exp = Experiment(T, {"F": on}, {"x": np.zeros_like(T)}, {"F": "N", "x": "m"})
    runs = OutputSimulator(late, exp).run_batch([{"F0": -2.0}, {"F0": 3.0}, {"F0": 3.0, "T_F": 0.25}])
    for run, (F0, delay) in zip(runs, ((-2.0, 0.5), (3.0, 0.5), (3.0, 0.25))):
        ref = simulate(msd, (0.0, T[-1]), inputs={"F": (T, np.where(T < delay, F0, 1.0))}, output_interval=DT,
                       method="RK4", dt=DT / 4)
        assert np.abs(run.outputs["x"] - ref["x"]).max() < 1e-6 * np.abs(ref["x"]).max()
    # saved and loaded, the name stays a name; exported, the Pade states start at its value
    save(late, tmp_path / "late.json")
    assert load(tmp_path / "late.json").equations().input_delays["F_late"].before == "F0"
    assert late.with_delays_realised().equations().initial_state["z1_F_late"] == -2.0


def test_a_value_before_named_but_not_declared_is_refused(msd):
    g = msd.copy()
    g.add_parameter(Param("T_F", 0.1, "s"))
    g.add_input("G", delay_of="F", delay="T_F", before="F_missing")
    with pytest.raises(DerivationError, match="'F_missing', is not a parameter"):
        g.equations()
    with pytest.raises(GraphError, match="neither a number nor a parameter"):
        msd.copy().add_input("H", delay_of="F", delay="T_F", before="1 N")
    with pytest.raises(GraphError, match="both named 'T_F'"):
        msd.delay_input("F", "T_F", 0.1, before=Param("T_F", 0.0))


def test_a_part_of_a_record_reads_the_commands_before_it(msd):
    # the held-out part of a record starts mid-run: the mass there, 0.3 s late, feels the force of
    # the training part's last 0.3 s, not the value before the record (0 N, delay_input's before)
    late = msd.delay_input("F", "T_F", 0.3, before=0.0)
    exp = Experiment(T, {"F": F}, {"x": np.zeros_like(T)}, {"F": "N", "x": "m"})
    whole = OutputSimulator(late, exp).run()
    train, hold = exp.split(0.4)
    assert hold.history.t.size == train.t.size and hold.history.t[-1] < hold.t[0]
    k = train.t.size
    for part in (hold, exp.samples(k, T.size), exp.samples(k, T.size).samples(2, 100)):
        start = int(np.searchsorted(T, part.t[0]))
        state = dict(zip(whole.state_names, whole.states[start]))
        seen = OutputSimulator(late, part).run(x0=state).outputs["x"]
        assert np.abs(seen - whole.outputs["x"][start:start + part.t.size]).max() < 1e-12
    # a part with no history (built from arrays) still takes the value before the record
    bare = Experiment(hold.t, hold.inputs, hold.outputs, hold.units)
    assert bare.history is None
    state = dict(zip(whole.state_names, whole.states[k]))
    assert np.abs(OutputSimulator(late, bare).run(x0=state).outputs["x"][:5]
                  - whole.outputs["x"][k:k + 5]).max() > 1e-6
