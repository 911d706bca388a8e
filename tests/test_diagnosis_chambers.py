"""Leaks and wall heat exchange in the PAM chambers are places: diagnosis on recordings of a
hand-written truth (gas mass and temperature as states, its own valve law and RK4), not the
catalogue's code.

The joint is locked (psi = 0: the chambers keep their volume), so the truth is two chambers
filled and vented by their valves; the nominal is the library's ``pam-locked``.
"""
import math

import numpy as np
import pytest

from plants.library.pam import KAPPA_KNOTS, PARAMETERS, pam
from diagnosis.diagnose import diagnose

P = {name: spec.value for name, spec in PARAMETERS.items()}
GAMMA = 1.4
CV = P["R"] / (GAMMA - 1.0)
KNOT_U, KNOT_A = zip(*KAPPA_KNOTS)
V0 = P["D1"] * P["L0"] ** 2 + P["D2"] * P["L0"] + P["D3"]          # chamber volume at psi = 0, m^3
SIGMA = {"P1": 400.0, "P2": 400.0, "tau": 0.01}                    # Pa, Pa, N m


def _flux(pa, pb):
    """Compressible-orifice mass flux a -> b per unit area, kg/(s m^2), signed."""
    k, up, down = P["k"], max(pa, pb), min(pa, pb)
    x = max(down / up, (2 / (k + 1)) ** (k / (k - 1)))
    mag = up * math.sqrt(2 * k / (P["R"] * (k - 1) * P["T"])) * x ** (1 / k) * math.sqrt(1 - x ** ((k - 1) / k))
    return math.copysign(mag, pa - pb) if pa != pb else 0.0


def _valve(u, p):
    """Mass flow into the chamber through the proportional valve, kg/s (eq. (5) of the PAM paper)."""
    a = float(np.interp(min(max(u, 0.0), 10.0), KNOT_U, KNOT_A))
    net = a * _flux(P["P_tank"], p) - (1 - a) * _flux(p, P["P_out"])
    return (P["A1"] if net > 0 else P["A2"]) * net


def _truth(t, u1, u2, *, leak=0.0, hA=None):
    """Per chamber: m' = valve - leak (P - P_out); with hA (W/K) the gas temperature is a state:
    c_v (m T)' = c_p T_in m'_in - c_p T m'_out + hA (T_wall - T); without it T = T_wall."""
    m = np.full(2, P["P_out"] * V0 / (P["R"] * P["T"]))
    temp = np.full(2, P["T"])
    out = {k: np.empty(t.size) for k in ("P1", "P2", "tau")}

    def rate(m, temp, u):
        p = m * P["R"] * temp / V0
        dm, dT = np.empty(2), np.zeros(2)
        for i in range(2):
            flow = _valve(u[i], p[i])
            dm[i] = flow - leak * (p[i] - P["P_out"])
            if hA is not None:
                t_in = P["T"] if flow > 0 else temp[i]
                dT[i] = (GAMMA * CV * t_in * max(flow, 0) + GAMMA * CV * temp[i] * min(flow, 0)
                         - GAMMA * CV * temp[i] * leak * (p[i] - P["P_out"])
                         - CV * temp[i] * dm[i] + hA * (P["T"] - temp[i])) / (m[i] * CV)
        return dm, dT

    h = 2.5e-4
    for k in range(t.size):
        p = m * P["R"] * temp / V0
        force = [(P[f"p_v1{i}"] * P["L0"] + P[f"p_v2{i}"]) * p[i - 1] + P[f"p_w1{i}"] * P["L0"] + P[f"p_w2{i}"]
                 for i in (1, 2)]
        out["P1"][k], out["P2"][k], out["tau"][k] = p[0], p[1], P["r"] * (force[0] - force[1])
        for _ in range(4):     # RK4, 4 sub-steps per 1 ms sample, inputs held
            u = (u1[k], u2[k])
            a = rate(m, temp, u)
            b = rate(m + h / 2 * a[0], temp + h / 2 * a[1], u)
            c = rate(m + h / 2 * b[0], temp + h / 2 * b[1], u)
            d = rate(m + h * c[0], temp + h * c[1], u)
            m = m + h / 6 * (a[0] + 2 * b[0] + 2 * c[0] + d[0])
            temp = temp + h / 6 * (a[1] + 2 * b[1] + 2 * c[1] + d[1])
    return out


def _recording(path, seed, **effect):
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, 6.0, 1e-3)
    hold = np.repeat(rng.uniform(1.0, 9.0, (2, 13)), 500, axis=1)[:, :t.size]   # levels held 0.5 s
    y = _truth(t, hold[0], hold[1], **effect)
    cols = {"t": t, "u1": hold[0], "u2": hold[1]}
    cols.update({k: y[k] + rng.normal(0.0, SIGMA[k], t.size) for k in y})
    lines = [",".join(cols)] + [",".join(f"{v:.9g}" for v in row) for row in zip(*cols.values())]
    path.write_text("\n".join(lines) + "\n")
    return path


def _diagnose(path, nominal):
    report = diagnose(nominal, str(path), inputs=["u1=u1", "u2=u2"], outputs=["P1=P1", "P2=P2", "tau=tau"],
                      max_effects=2)
    return report.to_json()


def test_a_leak_from_both_chambers_is_found_at_the_chambers(tmp_path):
    isothermal = pam("locked", params={"k1": 1.0, "k2": 1.0})     # the truth's chambers without a leak
    report = _diagnose(_recording(tmp_path / "leak.csv", 1, leak=2e-11), isothermal)
    found = report["missing_physics"]
    assert [f["kind"] for f in found] == ["leak", "leak"]
    assert {f["attached_to"] for f in found} == {"junction chamber1", "junction chamber2"}
    for f in found:
        (value,) = [v for k, v in f["parameters"].items() if k.startswith("c_leak")]
        assert value == pytest.approx(2e-11, rel=0.25)          # kg/(s Pa)
    fit = report["fit"]
    assert fit["improved"]["P1"] < 0.5 * fit["nominal"]["P1"]


def test_wall_heat_exchange_is_found_in_an_isothermal_chambers_model(tmp_path):
    isothermal = pam("locked", params={"k1": 1.0, "k2": 1.0})
    report = _diagnose(_recording(tmp_path / "heat.csv", 2, hA=0.2), isothermal)
    found = report["missing_physics"]
    assert found and {f["kind"] for f in found} == {"heat_transfer"}
    assert {f["attached_to"] for f in found} <= {"junction chamber1", "junction chamber2"}
    fit = report["fit"]
    assert fit["improved"]["P1"] < 0.5 * fit["nominal"]["P1"]


def test_twin_places_are_the_repeated_components():
    from plants import library
    from diagnosis.catalogue import candidates
    from diagnosis.place import Place
    from diagnosis.twins import CandidateGroup, twin_places
    from diagnosis.graph_location import candidate_places

    g = pam("locked")
    places = candidate_places(g)
    assert [p.name for p in twin_places(g, Place("junction", "chamber1"), places)] == ["chamber2"]
    assert twin_places(g, Place("input", "u1"), places) == [Place("input", "u2")]
    msd = library.build("mass-spring-damper")
    assert twin_places(msd, Place("junction", "v_mass"), candidate_places(msd)) == []
    leaks = [next(c for c in candidates(g, Place("junction", j)) if c.kind == "leak") for j in ("chamber1", "chamber2")]
    group = CandidateGroup(tuple(leaks))
    assert [p.name for p in group.params] == ["c_leak_chamber1", "c_leak_chamber2"]
    built = group.build(g, {"c_leak_chamber1": 1e-11, "c_leak_chamber2": 2e-11})
    assert {"leak_chamber1", "leak_chamber2"} <= set(built.elements)
    assert built.parameters()["c_leak_chamber2"].value == 2e-11
    assert str(group) == "leak at junction chamber1, junction chamber2"
    assert group.explain().count("a leak at") == 2


def test_a_twin_group_whose_member_ends_idle_answers_with_the_member_that_acts():
    """Fitted at both chambers, a leak of one chamber ends at 0 at the other (seed 2929, case 004:
    9.9e-20 against 2.77e-13 kg/s/Pa): the answer is the single leak that acts, with its values, its
    price and its graph; a group whose members all act, or all idle, stays as it is."""
    from diagnosis.catalogue import candidates
    from diagnosis.fit import CandidateFit
    from diagnosis.place import Place
    from diagnosis.twins import IDLE, CandidateGroup, without_idle_members

    g = pam("locked")
    leaks = [next(c for c in candidates(g, Place("junction", j)) if c.kind == "leak") for j in ("chamber2", "chamber1")]
    group = CandidateGroup(tuple(leaks))
    guess = leaks[0].params[0].guess

    def fitted(c2, c1):
        values = {"c_leak_chamber2": c2 * guess, "c_leak_chamber1": c1 * guess}
        return CandidateFit(group, values, {"P1": 0.01}, {"P1": 0.02}, group.n_params, True, "", group.build(g))

    answer = without_idle_members(fitted(0.1 * IDLE, 0.3), g)
    assert answer.candidate is leaks[1] and answer.values == {"c_leak_chamber1": 0.3 * guess}
    assert answer.n_params == group.n_params - 1 and answer.holdout_nrmse == {"P1": 0.02}
    assert "leak_chamber1" in answer.graph.elements and "leak_chamber2" not in answer.graph.elements
    assert answer.extra["idle_twins"] == ["junction chamber2"]
    for c2, c1 in ((10 * IDLE, 0.3), (0.0, 0.0)):
        assert without_idle_members(fitted(c2, c1), g).candidate is group
