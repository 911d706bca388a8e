"""Where an actuator rested before the record began (diagnosis.kinds.signal_common.resting_input).

An actuator lag or delay starts from the input's value before t = 0.  A recording that starts at
rest tells it: the input at which the recording's initial state is at rest.  References: the PAM
joint's rest at 5 V on both valves (the benchmark's hand-written truth, its own bisection for the
static pressures, eqs. (4)-(5)); a free mass and a mass-spring at rest need no force.
"""
import numpy as np
import pytest

import plants
from diagnosis.benchmark.effects import make_effect
from diagnosis.benchmark.plants import PLANTS
from diagnosis.benchmark.simulate import simulate_truth
from diagnosis.catalogue import candidates
from diagnosis.kinds.signal_common import resting_input
from diagnosis.place import Place
from diagnosis.recording import Experiment


def test_a_valve_that_held_the_joint_at_rest_rested_at_5_volts():
    truth = PLANTS["pam"]()
    pam = plants.load("pam")
    commands = np.array([7.3, 2.0, 9.1, 0.6])        # none of them is the valve's rest
    assert resting_input(pam, "u1", commands, truth.nominal_x0) == pytest.approx(5.0, abs=1e-3)
    # the lag's state starts there, read from the recording's initial state
    t = np.arange(1000) * 1e-3
    held = np.repeat(commands, 250)
    exp = Experiment(t, {"u1": held, "u2": held}, {"psi": np.zeros(t.size)}, {"u1": "V", "u2": "V", "psi": "deg"},
                     "test")
    lag = next(c for c in candidates(pam, Place("input", "u1"), experiment=exp, x0=truth.nominal_x0)
               if c.kind == "valve_lag")
    assert lag.initial["x_lag_u1"] == pytest.approx(5.0, abs=1e-3)


def test_a_mass_at_rest_had_no_force_whatever_its_first_command():
    for model, u in (("carriage", "F"), ("mass-spring-damper", "F")):
        assert resting_input(plants.load(model), u, np.array([6.7, -5.3, 1.0])) == 0.0


def test_the_benchmarks_delay_delivers_the_ambient_value_before_its_first_sample():
    plant = PLANTS["carriage"]()
    t = np.arange(0.0, 1.0, 1.0 / plant.rate)
    u = {"F": np.full(t.size, 3.0)}
    delay = make_effect("transport_delay", plant, "input", "F", 0.2, {}, {"u0": 0.0})
    seen = delay.delayed_inputs(t, u)["F"]
    k = int(round(0.2 * plant.rate))
    assert np.all(seen[:k] == 0.0) and np.all(seen[k:] == 3.0)
    # so the carriage stays at rest until the delayed step arrives
    x = simulate_truth(plant, t, u, delay)["x"]
    assert np.all(x[:k] == 0.0) and x[-1] > 0.0


def test_where_the_state_cannot_tell_the_delayed_input_s_value_before_is_fitted():
    """The cylinder rig's rod force reads the chamber pressure directly (F = p A) and its motion is
    imposed: no state says where the pressure rested before the record.  The benchmark's
    hand-written truth delays the pressure 0.19 s (19 samples) from a rest at 0 Pa, and the record
    starts at 3 bar: the delay alone (before = the first command) leaves the first 0.19 s
    147 N wrong; with its value before the record fitted, both are found and F is exact."""
    from diagnosis.benchmark.plants_cylinder import triangle_strokes
    from diagnosis.fit import fit_candidate

    plant = PLANTS["pneumatic-cylinder"]()
    t = np.arange(0.0, 20.0, 1.0 / plant.rate)
    u = {"p": np.repeat([3.0e5, 6.0e5, 2.0e5, 5.0e5], t.size // 4), "x": triangle_strokes(t)}
    y = simulate_truth(plant, t, u, make_effect("transport_delay", plant, "input", "p", 0.19, {}, {"u0": 0.0}))
    exp = Experiment(t, u, {"F": y["F"], "v_piston": y["v_piston"]}, {"p": "Pa", "x": "m", "F": "N",
                                                                       "v_piston": "m/s"}, "delayed pressure")
    train, hold = exp.split(0.3)
    graph = plants.load("pneumatic-cylinder")
    assert resting_input(graph, "p", u["p"]) == u["p"][0]       # the state cannot tell: the first command
    cand = next(c for c in candidates(graph, Place("input", "p"), experiment=train) if c.kind == "transport_delay")
    assert [p.name for p in cand.params] == ["T_delay_p", "p_before"] and not cand.params[1].priced
    fit = fit_candidate(graph, cand, train, hold)
    assert fit.values["T_delay_p"] == pytest.approx(0.19, abs=1e-6)
    assert fit.values["p_before"] == pytest.approx(0.0, abs=1e-3 * 6e5)
    assert fit.train_nrmse["F"] < 1e-6
