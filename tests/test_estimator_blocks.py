"""UKFBlock: the UKF as a co-simulation component equals the same filter run by hand."""
import numpy as np
import pytest

from plants.blockdiagram import pam as pam_bd
from bondgraph.errors import CosimError, UnknownNameError
from bondgraph.numerics.evaluate import compile_model
from plants.library import build
from cosim import CoSimulation, FMUComponent, Function
from cosim.estimator_blocks import UKFBlock
from reproductions._pam_sensorless_loop import (UKF_P0, UKF_Q, UKF_R, DiscretePIBlock,
                                                  PressureSensors)
from estimators import DiscretePI, JulierSigmaPoints, StateMap, UnscentedKalmanFilter
from fmus import export

DT = 1e-3    # s, the paper's sample time
N = 800      # communication steps per run


@pytest.fixture(scope="module")
def pam_model():
    model = compile_model(build("pam").equations())
    J = model.default_params[model.param_index["J"]]
    smap = StateMap.scaled(model.state_names, {"psi": ("q_psi", 1.0), "dpsi": ("p_J", J),
                                               "P1": ("P_1", 1.0), "P2": ("P_2", 1.0)},
                           units=("rad", "rad/s", "Pa", "Pa"))
    return model, smap


@pytest.fixture(scope="module")
def plant_fmu(tmp_path_factory):
    # the plant differs from the filter's model (wider filling orifice), as a rig would
    return export(build("pam"), tmp_path_factory.mktemp("ukfblock") / "pam.fmu",
                  params={"A1": 5.184e-8 * 1.15})


def ukf_options(smap, x0):
    return dict(dt=DT, outputs=("P1", "P2"), x0=x0, P0=UKF_P0, Q=UKF_Q, R=UKF_R,
                points=JulierSigmaPoints(4, kappa=0.0), state_map=smap)


X0 = np.array([np.radians(5.0), 0.0, 3.5e5, 4.5e5])   # a wrong initial estimate (rad, rad/s, Pa, Pa)


@pytest.fixture(scope="module")
def closed_loop(pam_model, plant_fmu):
    """Angle PI on the UKF estimate around the plant FMU, noisy pressures: the logged run."""
    model, smap = pam_model
    rest = pam_bd.equilibrium([5.5, 5.5])
    plant = FMUComponent(plant_fmu, "plant", start_values={
        "u1": 5.5, "u2": 5.5, "P_1": rest[2], "P_2": rest[3], "q_psi": rest[0]})
    ukf = UKFBlock.from_model("ukf", model, estimates=("psi", "tau"), **ukf_options(smap, X0))
    sim = CoSimulation(
        [Function("ref", lambda t: 10.0 * np.sin(2 * np.pi * t), unit="deg"),
         DiscretePIBlock("pi", DiscretePI.from_paper("angle"), "deg"), ukf,
         PressureSensors("sensors", 1e4, np.random.default_rng(5)), plant],
        [("ref.y", "pi.r"), ("ukf.psi_hat", "pi.y_m"), ("pi.u1", "plant.u1"), ("pi.u2", "plant.u2"),
         ("pi.u1", "ukf.u1"), ("pi.u2", "ukf.u2"), ("plant.P1", "sensors.P1_true"),
         ("plant.P2", "sensors.P2_true"), ("sensors.P1", "ukf.P1"), ("sensors.P2", "ukf.P2")],
        step=DT)
    return sim, sim.run(N * DT)


def logged(res, names):
    return np.column_stack([res[n] for n in names])


def test_block_equals_batch_filter_on_the_logged_signals(pam_model, closed_loop):
    """Same filter, same logged z (noisy P1, P2) and u (valve commands): estimates equal to 1e-12."""
    model, smap = pam_model
    _, res = closed_loop
    z, u = logged(res, ["sensors.P1", "sensors.P2"]), logged(res, ["pi.u1", "pi.u2"])
    by_hand = UnscentedKalmanFilter.from_model(model, **ukf_options(smap, X0)).batch_filter(z, u)
    block = logged(res, ["ukf.x_psi", "ukf.x_dpsi", "ukf.x_P1", "ukf.x_P2"])
    scale = np.abs(by_hand.x).max(axis=0)
    np.testing.assert_allclose(block, by_hand.x, rtol=0, atol=1e-12 * scale.max())
    assert (np.abs(block - by_hand.x) <= 1e-12 * scale).all()
    assert np.ptp(block[:, 0]) > np.radians(5.0)     # the loop moved the joint


def test_block_equals_predict_update_by_hand(pam_model, closed_loop):
    """The paper's recursion x(k) = UKF(x(k-1), P(k-1), u(k-1), y(k)) written out, numpy engine:
    equal to rounding of the two engines; the estimated outputs are h at the estimate."""
    model, smap = pam_model
    _, res = closed_loop
    z, u = logged(res, ["sensors.P1", "sensors.P2"]), logged(res, ["pi.u1", "pi.u2"])
    ukf = UnscentedKalmanFilter.from_model(model, kernel="numpy", **ukf_options(smap, X0))
    xs = [ukf.x]
    for k in range(1, N + 1):
        ukf.predict(u[k - 1])
        ukf.update(z[k])
        xs.append(ukf.x)
    xs = np.array(xs)
    block = logged(res, ["ukf.x_psi", "ukf.x_dpsi", "ukf.x_P1", "ukf.x_P2"])
    np.testing.assert_allclose(block, xs, rtol=1e-9, atol=1e-12)
    u_used = np.vstack([model.default_inputs, u[:-1]])     # the block's h uses the last predict's input
    y = model.h(smap.to_model(xs), u_used)
    np.testing.assert_allclose(res["ukf.psi_hat"], y[:, model.output_index["psi"]], rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(res["ukf.tau_hat"], y[:, model.output_index["tau"]], rtol=1e-9, atol=1e-9)
    # the estimate follows the plant (5 deg wrong at t = 0): RMSE after 0.3 s well under the start error
    late = res.t >= 0.3
    assert np.sqrt(np.mean((res["ukf.psi_hat"] - res["plant.psi"])[late] ** 2)) < 1.0


def test_ports_units_and_feedthrough(pam_model, closed_loop):
    """Measurements feed through to every output, plant inputs to none (no loop via the PI)."""
    sim, res = closed_loop
    block = sim.components["ukf"]
    assert [(p.name, p.unit) for p in block.inputs] == [("P1", "Pa"), ("P2", "Pa"), ("u1", "V"), ("u2", "V")]
    assert [(p.name, p.unit) for p in block.outputs] == [
        ("x_psi", "rad"), ("x_dpsi", "rad/s"), ("x_P1", "Pa"), ("x_P2", "Pa"),
        ("psi_hat", "deg"), ("tau_hat", "N m")]
    assert {i for i, _ in block.feedthrough} == {"P1", "P2"}
    assert len(block.feedthrough) == 2 * 6
    assert res.units["ukf.tau_hat"] == "N m"
    assert res["ukf.x_psi"][0] == X0[0]           # t0: the initial estimate, no update yet
    assert sim.order.index("ukf") < sim.order.index("pi")


def test_bad_set_ups_are_named(pam_model, plant_fmu):
    model, smap = pam_model
    python_ukf = UnscentedKalmanFilter(fx=lambda X, u: X, hx=lambda X, u: X, x0=[0.0], P0=[[1.0]],
                                       Q=[[0.0]], R=[[1.0]], points=JulierSigmaPoints(1))
    with pytest.raises(CosimError, match="'est'.*from_model"):
        UKFBlock("est", python_ukf)
    with pytest.raises(UnknownNameError, match="torque"):
        UKFBlock.from_model("ukf", model, estimates=("torque",), **ukf_options(smap, X0))
    with pytest.raises(TypeError, match="ouputs"):
        UKFBlock.from_model("ukf", model, ouputs=("P1",), **ukf_options(smap, X0))
    block = UKFBlock.from_model("ukf", model, **ukf_options(smap, X0))
    sim = CoSimulation([block, Function("p", lambda t: 3e5, unit="Pa")],
                       [("p.y", "ukf.P1"), ("p.y", "ukf.P2")], step=2 * DT)
    with pytest.raises(CosimError, match=r"'ukf'.*step 0\.002 s differs.*dt = 0\.001"):
        sim.run(4 * DT)
    sim = CoSimulation([UKFBlock.from_model("ukf", model, **ukf_options(smap, X0)),
                        Function("p", lambda t: 3e5, unit="Pa")],
                       [("p.y", "ukf.P1"), ("p.y", "ukf.P2")], step=DT)
    sim.run(2 * DT)
    with pytest.raises(CosimError, match="'ukf'.*after 2 step"):   # a second run needs a new block
        sim.run(2 * DT)
