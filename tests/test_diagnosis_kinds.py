"""Issue 11's vocabulary: a friction set by any signal through a lag, Coulomb and viscous friction
as one law, a cubic spring refitted with its own linear value.

Every recording comes from a truth written here by hand (numpy RK4 or its own bond-graph
elements), never from the candidate's build."""
import numpy as np
import pytest

from bondgraph import R
from bondgraph.io_json import graph_from_dict
import plants.library as library
from plants.library.textbook import mass_spring_damper
from diagnosis.catalogue import candidates
from diagnosis.fit import choose, fit_candidate, noise_floor
from diagnosis.place import Place
from diagnosis.recording import Experiment
from diagnosis.residuals import OutputSimulator, nrmse

T = np.linspace(0.0, 20.0, 1001)                      # 50 Hz, 20 s
F = np.where(T % 6.0 < 3.0, 2.0, -1.0) + 0.5 * np.sin(0.7 * T)
UNITS = {"F": "N", "x": "m", "v": "m/s"}


def _msd_record(truth, rng, noise=0.01):
    y = OutputSimulator(truth, Experiment(T, {"F": F}, {"x": T, "v": T}, UNITS))()
    y = {k: v + noise * np.std(v) * rng.standard_normal(v.size) for k, v in y.items()}
    return Experiment(T, {"F": F}, y, UNITS)


def _holdout(graph, exp, hold):
    sim = OutputSimulator(graph, exp)()
    mask = exp.t >= hold.t[0]
    return {o: nrmse(hold.outputs[o], sim[o][mask]) for o in hold.outputs}


def _fits(graph, place, train, hold, kinds):
    cands = [c for c in candidates(graph, place, experiment=train) if c.kind in kinds]
    return {c.kind: fit_candidate(graph, c, train, hold) for c in cands}


# -- modulated friction: an MR damper -------------------------------------------------------------

def _damper_rig():
    """The cylinder rig's graph (imposed rod position, force measured) with the damper's coil
    voltage ``V`` declared as a recorded input the nominal model does not use; p held at 0."""
    data = library.build("pneumatic-cylinder").to_dict()
    data["inputs"].append({"name": "V", "default": 0.0, "unit": "V", "description": "coil voltage"})
    return graph_from_dict(data)


def _mr_damper_recording(rng, *, f0=20.0, k=15.0, tau=0.08, fs=200.0, duration=30.0):
    """Hand-written MR damper: rod strokes (follower, 20 ms), coil voltage held 0.3-1.2 s at random
    levels in 0-5 V, yield force (f0 + k V_lag) tanh(v / 1 mm/s) with V_lag' = (V - V_lag)/tau."""
    n = int(duration * fs) + 1
    t = np.arange(n) / fs
    x = 0.02 + 0.015 * np.sin(2 * np.pi * t / 1.7)
    volts = np.empty(n)
    i = 0
    while i < n:
        j = i + int(rng.uniform(0.3, 1.2) * fs)
        volts[i:j] = rng.uniform(0.0, 5.0)
        i = j
    tau_s, h = 0.02, 1.0 / fs
    xs, lag = 0.0, volts[0]
    force, vel = np.empty(n), np.empty(n)
    for m in range(n):
        v = -(x[m] - xs) / tau_s
        vel[m] = v
        force[m] = -(f0 + k * lag) * np.tanh(v / 1e-3)

        def rates(s):
            return np.array([(x[m] - s[0]) / tau_s, (volts[m] - s[1]) / tau])
        s = np.array([xs, lag])
        k1 = rates(s)
        k2 = rates(s + h / 2 * k1)
        k3 = rates(s + h / 2 * k2)
        k4 = rates(s + h * k3)
        xs, lag = s + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    force = force + 0.5 * rng.standard_normal(n)
    return Experiment(t, {"p": np.zeros(n), "x": x, "V": volts}, {"F": force, "v_piston": vel},
                      {"p": "Pa", "x": "m", "V": "V", "F": "N", "v_piston": "m/s"})


def test_modulated_friction_recovers_an_mr_dampers_level_gain_and_lag(rng):
    rig = _damper_rig()
    exp = _mr_damper_recording(rng)
    train, hold = exp.split(0.3)
    place = Place("junction", "piston")
    offered = [c for c in candidates(rig, place, experiment=train) if c.kind == "modulated_friction"]
    # p is constant (nothing to modulate), x drives the piston (the motion's cause): the coil only
    assert [c.regime for c in offered] == ["V"]
    coil = next(c for c in offered if c.regime == "V")
    fit = fit_candidate(rig, coil, train, hold)
    values = fit.values
    level_at_mean = 20.0 + 15.0 * coil.constants[0][1]              # F0 is the level at the mean voltage
    assert values["F0_piston_V"] == pytest.approx(level_at_mean, rel=0.05)
    assert values["k_mod_piston_V"] == pytest.approx(15.0, rel=0.05)
    assert values["tau_mod_piston_V"] == pytest.approx(0.08, rel=0.15)
    others = _fits(rig, place, train, hold, ("coulomb_friction", "stribeck_friction", "hysteresis"))
    nominal = _holdout(rig, exp, hold)
    chosen = choose(nominal, [fit, *others.values()], noise=noise_floor(hold))
    assert chosen is fit
    assert fit.holdout_nrmse["F"] < 0.3 * min(f.holdout_nrmse["F"] for f in others.values())
    assert "following V with a lag of 0.0" in coil.explain(values)


def test_modulated_friction_starts_with_a_level_that_stays_positive(rng):
    """A friction's level is never negative: every start keeps ``F0 + k (V - V_ref)`` at or above
    a tenth of F0 over the recorded voltages (a slope of 30 % of the effort scale against a small
    level made the pam's seesaw run on with the motion: seed 5757, case 043)."""
    rig, place = _damper_rig(), Place("junction", "piston")
    train, _ = _mr_damper_recording(rng).split(0.3)
    coil = next(c for c in candidates(rig, place, experiment=train) if c.kind == "modulated_friction")
    v_ref, volts = coil.constants[0][1], train.inputs["V"]
    levels = [s["F0_piston_V"] + s["k_mod_piston_V"] * (volts - v_ref) for s in coil.starts]
    assert all(np.min(level) >= 0.1 * s["F0_piston_V"] * (1 - 1e-9) for level, s in zip(levels, coil.starts))
    assert {np.sign(s["k_mod_piston_V"]) for s in coil.starts} == {-1.0, 1.0}     # both slopes still tried


def test_modulated_friction_starts_where_the_feature_regression_found_it(rng):
    """The regression on the damper's located residual picks the lag of its grid nearest the
    truth's (20 samples = 0.1 s; truth 0.08 s) and estimates level and gain: that start is closer
    than every guess of the catalogue's (lags 2, 20, 200 samples, slopes +-30 % of the effort
    scale), by training cost."""
    from diagnosis.features import feature_evidence, with_feature_starts
    rig, place = _damper_rig(), Place("junction", "piston")
    train, _ = _mr_damper_recording(rng).split(0.3)
    coil = next(c for c in candidates(rig, place, experiment=train) if c.kind == "modulated_friction")
    evidence = feature_evidence(rig, [place], train)
    started = with_feature_starts([coil], evidence)[0]
    assert len(started.starts) == len(coil.starts) + 1
    start = started.starts[-1]
    assert start["tau_mod_piston_V"] == pytest.approx(0.1)
    assert start["k_mod_piston_V"] == pytest.approx(15.0, rel=0.3)
    assert start["F0_piston_V"] == pytest.approx(20.0 + 15.0 * coil.constants[0][1], rel=0.3)
    sim = OutputSimulator(coil.build(rig), train)

    def cost(values):
        y = sim(values)
        return sum(nrmse(train.outputs[o], y[o]) ** 2 for o in train.outputs)
    assert cost(start) < min(cost(s) for s in coil.starts)


# -- Coulomb + viscous as one law -------------------------------------------------------------

def test_coulomb_and_viscous_friction_are_fitted_together(rng):
    """Truth: the msd with a seal 0.3 N tanh(v / 0.02) and an extra 0.5 N s/m of viscous loss."""
    truth = mass_spring_damper(b=0.4)
    truth.add(R("seal", effort="Fc_true*tanh(f/v_true) + b_true*f",
                params={"Fc_true": 0.3, "v_true": 0.02, "b_true": 0.5}, domain="translation"))
    truth.connect("v_mass", "seal")
    msd = library.build("mass-spring-damper")
    train, hold = _msd_record(truth, rng).split(0.3)
    fits = _fits(msd, Place("junction", "v_mass"), train, hold,
                 ("coulomb_friction", "viscous_friction", "coulomb_viscous_friction", "stribeck_friction"))
    both = fits["coulomb_viscous_friction"]
    assert both.values["Fc_v_mass"] == pytest.approx(0.3, rel=0.1)
    assert both.values["b_visc_v_mass"] == pytest.approx(0.5, rel=0.1)
    exp = _msd_record(truth, np.random.default_rng(1))
    assert choose(_holdout(msd, exp, hold), list(fits.values()), noise=noise_floor(hold)) is both


def test_coulomb_friction_alone_is_not_answered_with_a_viscous_term(rng):
    truth = mass_spring_damper(b=0.4)
    truth.add(R("seal", effort="Fc_true*tanh(f/v_true)", params={"Fc_true": 0.3, "v_true": 0.02},
                domain="translation"))
    truth.connect("v_mass", "seal")
    msd = library.build("mass-spring-damper")
    exp = _msd_record(truth, rng)
    train, hold = exp.split(0.3)
    fits = _fits(msd, Place("junction", "v_mass"), train, hold, ("coulomb_friction", "coulomb_viscous_friction"))
    assert choose(_holdout(msd, exp, hold), list(fits.values()), noise=noise_floor(hold)).kind == "coulomb_friction"


# -- viscous friction harder one way -----------------------------------------------------------

def _one_way_record(rng, b_fwd, b_back, noise=0.01):
    """Truth (tests/msd_truth.py, numpy RK4): the msd with an extra damping of b_fwd v while the
    mass moves forward and b_back v while it moves back (a shock absorber's compression and
    rebound); its position measured with noise a hundredth of its spread."""
    from msd_truth import msd_positions
    x = msd_positions(T, F, lambda x, v: (b_fwd if v > 0 else b_back) * v)
    x = x + noise * np.std(x) * rng.standard_normal(x.size)
    return Experiment(T, {"F": F}, {"x": x}, UNITS)


def test_a_damping_harder_one_way_is_fitted_side_by_side_and_chosen(rng):
    """Truth: 0.8 N s/m more damping only while the mass moves back.  Viscous friction takes the
    mean of the two sides; the direction-dependent law recovers each and is chosen."""
    msd = library.build("mass-spring-damper")
    exp = _one_way_record(rng, 0.0, 0.8)
    train, hold = exp.split(0.3)
    fits = _fits(msd, Place("junction", "v_mass"), train, hold,
                 ("viscous_friction", "coulomb_viscous_friction", "asymmetric_viscous_friction"))
    one_way = fits["asymmetric_viscous_friction"]
    assert one_way.values["b_back_v_mass"] == pytest.approx(0.8, rel=0.05)
    assert one_way.values["b_fwd_v_mass"] == pytest.approx(0.0, abs=0.04)
    assert one_way.holdout_nrmse["x"] < 0.3 * fits["viscous_friction"].holdout_nrmse["x"]
    assert choose(_holdout(msd, exp, hold), list(fits.values()), noise=noise_floor(hold)) is one_way


def test_a_damping_that_depends_on_the_direction_is_offered_only_where_the_flow_reverses():
    """A force ramp drives the mass one way only (the nominal's velocity keeps its sign): there a
    direction-dependent law is viscous friction with a free coefficient for the side never seen."""
    from diagnosis.kinds.asymmetric_viscous_friction import goes_both_ways
    msd = library.build("mass-spring-damper")
    offered = {}
    for name, force in (("ramp", 0.1 * T), ("sine", np.sin(T))):
        exp = Experiment(T, {"F": force}, {"x": np.zeros(T.size)}, {"F": "N", "x": "m"}, name)
        offered[name] = [c.kind for c in candidates(msd, Place("junction", "v_mass"), experiment=exp)]
    assert "asymmetric_viscous_friction" not in offered["ramp"] and "viscous_friction" in offered["ramp"]
    assert "asymmetric_viscous_friction" in offered["sine"]
    assert goes_both_ways(np.sin(T)) and not goes_both_ways(np.abs(np.sin(T)) + 0.01)
    assert not goes_both_ways(np.concatenate([np.full(95, 1.0), np.full(5, -1.0)]))     # 5 % back: too few


def test_a_damping_alike_both_ways_is_answered_viscous(rng):
    """Truth: 0.5 N s/m more damping both ways: the two-sided law fits as well, with two
    parameters, and loses to viscous friction."""
    msd = library.build("mass-spring-damper")
    exp = _one_way_record(rng, 0.5, 0.5)
    train, hold = exp.split(0.3)
    fits = _fits(msd, Place("junction", "v_mass"), train, hold, ("viscous_friction", "asymmetric_viscous_friction"))
    chosen = choose(_holdout(msd, exp, hold), list(fits.values()), noise=noise_floor(hold))
    assert chosen is fits["viscous_friction"]
    assert chosen.values["b_visc_v_mass"] == pytest.approx(0.5, rel=0.05)


# -- quadratic drag ----------------------------------------------------------------------------

def _drag_record(rng, extra, noise=0.01):
    """Truth (tests/msd_truth.py, numpy RK4): the msd with the force `extra(v)` taken from the mass;
    its position measured with noise a hundredth of its spread."""
    from msd_truth import msd_positions
    x = msd_positions(T, F, lambda x, v: extra(v))
    x = x + noise * np.std(x) * rng.standard_normal(x.size)
    return Experiment(T, {"F": F}, {"x": x}, UNITS)


@pytest.mark.parametrize("truth, kind", [(lambda v: 0.4 * v * abs(v), "quadratic_drag"),
                                         (lambda v: 0.5 * v, "viscous_friction")], ids=["drag", "viscous"])
def test_a_drag_growing_with_the_speed_squared_is_told_from_viscous_friction(rng, truth, kind):
    """Truth: 0.4 N (s/m)^2 v |v| of drag (a fan, a body in water), or 0.5 N s/m of viscous friction:
    each kind recovers its coefficient and is chosen over the other."""
    msd = library.build("mass-spring-damper")
    exp = _drag_record(rng, truth)
    train, hold = exp.split(0.3)
    fits = _fits(msd, Place("junction", "v_mass"), train, hold,
                 ("viscous_friction", "coulomb_viscous_friction", "quadratic_drag"))
    chosen = choose(_holdout(msd, exp, hold), list(fits.values()), noise=noise_floor(hold))
    assert chosen is fits[kind]
    name, value = ("c_d_v_mass", 0.4) if kind == "quadratic_drag" else ("b_visc_v_mass", 0.5)
    assert chosen.values[name] == pytest.approx(value, rel=0.05)


# -- a cubic spring refits its own linear stiffness --------------------------------------------

def _cubic_truth(k_lin=3.0, k3=40.0):
    truth = mass_spring_damper(b=0.4)
    data = truth.to_dict()
    spring = next(e for e in data["elements"] if e["name"] == "k")
    spring.pop("stiffness"), spring.pop("unit", None)
    spring["law"] = "k_true*q + k3_true*q**3"
    spring["params"] = {name: {"name": name, "value": value, "unit": "", "description": "truth"}
                        for name, value in (("k_true", k_lin), ("k3_true", k3))}
    return graph_from_dict(data)


def test_nonlinear_stiffness_refits_the_springs_linear_stiffness(rng):
    """The nominal's k = 4 N/m is what a linear fit would give; the truth is 3 N/m + 40 N/m^3 q^3."""
    msd = library.build("mass-spring-damper")
    exp = _msd_record(_cubic_truth(), rng)
    train, hold = exp.split(0.3)
    cand = next(c for c in candidates(msd, Place("junction", "v_mass"), experiment=train)
                if c.kind == "nonlinear_stiffness")
    assert [p.name for p in cand.params] == ["k3_k", "k"]           # the spring's own parameter
    fit = fit_candidate(msd, cand, train, hold)
    assert fit.values["k"] == pytest.approx(3.0, rel=0.03)
    assert fit.values["k3_k"] == pytest.approx(40.0, rel=0.05)
    assert fit.holdout_nrmse["x"] < 0.05
    assert "linear stiffness of k refitted with it: 3" in cand.explain(fit.values)


def test_uncertain_stiffness_of_a_refitted_spring_survives_to_the_improved_model(rng, tmp_path):
    """``--uncertain k`` with the spring's own stiffness refitted by nonlinear_stiffness: the
    diagnosis finishes (it died after all fits with "cannot set fitted parameter(s) k") and the
    improved graph carries the fitted k."""
    from diagnosis.diagnose import diagnose
    exp = _msd_record(_cubic_truth(), rng)
    path = tmp_path / "rec.csv"
    np.savetxt(path, np.column_stack([exp.t, exp.inputs["F"], exp.outputs["x"], exp.outputs["v"]]),
               delimiter=",", header="t,F,x,v", comments="")
    report = diagnose("mass-spring-damper", str(path), inputs=["F=F"], outputs=["x=x", "v=v"],
                      uncertain=["k", "b"], max_effects=1)
    effect = report.to_json()["missing_physics"][0]
    assert effect["kind"] == "nonlinear_stiffness"
    assert effect["parameters"]["k"] == pytest.approx(3.0, rel=0.05)
    assert report.improved_graph.parameters()["k"].value == pytest.approx(effect["parameters"]["k"])


def test_backlash_with_an_uncertain_spring_sets_the_laws_own_parameter():
    """A candidate that moves a C's value into its law's own parameters (backlash) still lets the
    fitted uncertain value be set on the improved graph."""
    from diagnosis.diagnose import _with_values
    msd = library.build("mass-spring-damper")
    cand = next(c for c in candidates(msd, Place("junction", "v_mass")) if c.kind == "backlash")
    better = _with_values(cand.build(msd, {"b_play_k": 0.01}), {"k": 5.5})
    assert better.parameters()["k"].value == 5.5


def test_a_friction_is_modulated_by_no_input_that_drives_its_own_junction():
    """The force on the msd's mass, the rod position imposed on the cylinder's piston and the
    drivetrain's torques drive the mechanics; the cylinder's pressure (another domain, through the
    piston area) and the motor's voltage may set a friction level."""
    from diagnosis.kinds.modulated_friction import modulating_signals
    at = lambda model, j: list(modulating_signals(library.build(model), j))  # noqa: E731
    assert at("mass-spring-damper", "v_mass") == []
    assert at("pneumatic-cylinder", "piston") == ["p"]
    assert at("drivetrain", "dw_shaft") == []
    assert at("dc-motor", "w_motor") == ["V"]
    assert at("pam", "seesaw") == ["u1", "u2"]
