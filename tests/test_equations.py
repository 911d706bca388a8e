"""Derived state equations against hand derivations (symbolic difference == 0).

Hand derivations: Karnopp, Margolis & Rosenberg, *System Dynamics* (5th ed.),
ch. 5 (SCAP), 7.3 (derivative causality); each stated in its test.
"""
import numpy as np
import sympy as sp
import pytest

from bondgraph import BondGraph, C, CField, EquationElement, I, IField, MGY, MSe, MSf, MTF, One, R, Se, Sf
from plants import library


def S(name):
    return sp.Symbol(name, real=True)


def assert_same(derived, expected):
    """Each derived expression equals the hand derivation (simplify of the difference is 0)."""
    assert len(derived) == len(expected)
    for d, e in zip(derived, expected):
        assert sp.simplify(d - e) == 0, f"{d}  !=  {e}"


def test_mass_spring_damper():
    eqs = library.build("mass-spring-damper").equations()
    F, m, b, k, p, q = map(S, "F m b k p_m q_k".split())
    assert eqs.state_names == ("p_m", "q_k")
    assert_same(eqs.f, [F - b * p / m - k * q, p / m])
    assert_same(eqs.h, [q, p / m])
    assert eqs.units["p_m"] == "N s" and eqs.units["k"] == "N/m" and eqs.units["x"] == "m"


def test_dc_motor_gyrator_and_transformer():
    eqs = library.build("dc-motor").equations()
    V, tl, Ra, La, km, Jm, bm, n, bL, pL, pJ = map(S, "V tau_L Ra La km Jm bm n bL p_La p_Jm".split())
    i, w = pL / La, pJ / Jm
    # armature: L di/dt = V - Ra i - km w; rotor: J dw/dt = km i - bm w - n (bL n w + tau_L)
    assert_same(eqs.f, [V - Ra * i - km * w, km * i - bm * w - n * (bL * n * w + tl)])
    assert_same(eqs.h, [i, w, n * w])


def test_rlc():
    eqs = library.build("rlc").equations()
    V, Rs, L, Cs, p, q = map(S, "V Rs L Cs p_L q_Cs".split())
    assert_same(eqs.f, [V - Rs * p / L - q / Cs, p / L])


def test_coupled_tanks_nonlinear_orifices():
    eqs = library.build("coupled-tanks").equations()
    Q, rho, g, a12, a2, A1, A2, V1, V2 = map(S, "Q_in rho g_acc a12 a2 A1 A2 V1 V2".split())
    P1, P2 = rho * g * V1 / A1, rho * g * V2 / A2
    q12 = a12 * sp.sign(P1 - P2) * sp.sqrt(2 * sp.Abs(P1 - P2) / rho)
    q2 = a2 * sp.sqrt(2 * P2 / rho)
    assert_same(eqs.f, [Q - q12, q12 - q2])


def test_derivative_causality_reflected_inertia():
    """Rigid gear: J2 is dependent; J_eq = J1 + n^2 J2 (Karnopp et al. sec. 7.3)."""
    g = library.build("geared-inertias")
    eqs = g.equations()
    tau, J1, J2, n, b, p = map(S, "tau J1 J2 n b p_J1".split())
    assert eqs.state_names == ("p_J1",)
    assert_same(eqs.f, [J1 * (tau - b * p / J1) / (J1 + n**2 * J2)])
    assert_same(eqs.h, [p / J1, n * p / J1])
    assert [e for e, _ in eqs.report.derivative_storage] == ["J2"]
    assert "derivative causality: J2" in str(eqs.report)


def test_a_decaying_law_in_a_reduced_inertia_stays_finite_at_high_speed():
    """A Stribeck-like friction exp(-(w/w_s)^2) on the load side of a rigid gear: the reduced
    inertia's rate is solved over a common denominator, which must not take exp(-u) as 1/exp(u).
    Otherwise the rate read (... exp(+u))/exp(+u): inf/inf = NaN past w = 27 w_s."""
    from bondgraph.numerics import compile_model
    g = library.build("geared-inertias")
    g.add(R("peak", effort="Fs*exp(-(f/w_s)**2)", params={"Fs": 0.3, "w_s": 0.01}, domain="rotation"))
    g.connect("w2", "peak")
    model = compile_model(g.equations())
    p_J1 = 0.01 * 50.0 / 0.2          # J1 w1, with w2 = n w1 = 50 rad/s = 5000 w_s
    rate = model.f([p_J1], [0.0], p=model.param_vector(None))
    jac = model.jac_x([p_J1], [0.0], p=model.param_vector(None))
    assert np.all(np.isfinite(rate)) and np.all(np.isfinite(jac))
    # the peak has decayed: the rate is the one without it, (J1 tau - b p)/(J1 + n^2 J2) at tau = 0
    assert rate[0] == pytest.approx(-0.05 * p_J1 / (0.01 + 0.04 * 0.5), rel=1e-9)


def test_two_masses_on_one_junction():
    """Two masses on one 1-junction: v' = (F - b v)/(m1 + m2)."""
    g = BondGraph("two_masses")
    for e in (Se("F"), One("j"), I("m1", 1.0), I("m2", 3.0), R("b", 0.5)):
        g.add(e)
    for e in ("m1", "m2", "b"):
        g.connect("j", e)
    g.connect("F", "j")
    g.add_output("p2", "p_m2")
    eqs = g.equations()
    F, m1, m2, b, p1 = map(S, "F m1 m2 b p_m1".split())
    assert_same([eqs.f[0] / m1], [(F - b * p1 / m1) / (m1 + m2)])
    assert_same(eqs.h, [m2 * p1 / m1])  # the eliminated momentum is still an output


def test_linear_algebraic_loop_solved_symbolically():
    eqs = library.build("resistor-loop").equations()
    V, R1, R2, R3, Cc, q = map(S, "V R1 R2 R3 Cc q_Cc".split())
    v_th, r_th = V * R2 / (R1 + R2), R1 * R2 / (R1 + R2) + R3   # Thevenin equivalent
    assert_same(eqs.f, [(v_th - q / Cc) / r_th])
    assert eqs.algebraic == ()
    assert eqs.report.loops_solved_symbolically == (True,)
    assert eqs.report.arbitrary  # an R had to be given arbitrary causality


def test_nonlinear_algebraic_loop_kept_implicit():
    eqs = library.build("resistor-loop-nl").equations()
    assert len(eqs.algebraic) == 1 and eqs.report.loops_solved_symbolically == (False,)
    (z,), (r,) = eqs.algebraic, eqs.residuals
    values = {S("V"): 1.0, S("R1"): 1.0, S("R2"): 2.0, S("R3v"): 3.0, S("a3"): 0.5, S("Cc"): 0.5, S("q_Cc"): 0.1}
    v_mid = sp.nsolve(r.subs(values), z, 0.5)
    # independent check by Kirchhoff: i3 = i1 - i2; v_mid - v_C = R3 i3 + a3 i3^3
    i1, i2 = (1.0 - v_mid) / 1.0, v_mid / 2.0
    i3 = i1 - i2
    assert abs(v_mid - 0.2 - (3.0 * i3 + 0.5 * i3**3)) < 1e-12
    assert abs(eqs.f[0].subs(values).subs(z, v_mid) - i3) < 1e-12


def test_modulated_elements_and_time_source():
    g = BondGraph("modulated")
    g.add(Se("F", "2*sin(3*t)"))
    g.add(One("j"))
    g.connect("F", "j")
    g.add(I("m", 2.0))
    g.connect("j", "m")
    g.add(MTF("lever", "L0 + c*q_k", params={"L0": 0.5, "c": 0.1}))
    g.connect("j", "lever")
    g.add(One("j2"))
    g.connect("lever", "j2")
    g.add(C("k", stiffness=4.0))
    g.connect("j2", "k")
    g.add(MSe("drag", "-d*f_m*Abs(f_m)", params={"d": 0.3}))
    g.connect("drag", "j")
    eqs = g.equations()
    F, m, k, q, p, L0, c, d = map(S, "F m k q_k p_m L0 c d".split())
    v = p / m
    lever = L0 + c * q
    # force balance at j: F + drag - lever * (k q); spring velocity = lever * v
    assert_same(eqs.f, [F - d * v * sp.Abs(v) - lever * k * q, lever * v])
    assert sp.simplify(eqs.input_functions["F"] - 2 * sp.sin(3 * S("t"))) == 0


def test_modulated_gyrator():
    """Motor whose torque constant varies with speed: r(w) = km0 (1 + eps w)."""
    g = BondGraph("mgy")
    g.add(Se("V"))
    g.add(One("i"))
    g.connect("V", "i")
    for e in (I("La", 0.01), R("Ra", 2.0)):
        g.add(e)
        g.connect("i", e.name)
    g.add(MGY("gyr", "km0*(1 + eps*f_J)", params={"km0": 0.05, "eps": 0.01}))
    g.connect("i", "gyr")
    g.add(One("w"))
    g.connect("gyr", "w")
    for e in (I("J", 1e-3), R("b", 1e-4)):
        g.add(e)
        g.connect("w", e.name)
    eqs = g.equations()
    V, La, Ra, km0, eps, J, b, pL, pJ = map(S, "V La Ra km0 eps J b p_La p_J".split())
    i, w = pL / La, pJ / J
    r = km0 * (1 + eps * w)
    assert_same(eqs.f, [V - Ra * i - r * w, r * i - b * w])


def test_effort_source_through_modulated_transformer_into_dependent_storage_is_refused():
    """The C's stored charge would depend on its own (eliminated) state: reported, not guessed."""
    from bondgraph import DerivationError
    g = BondGraph("bad_dependent")
    g.add(MSe("Q", "2.0"))
    g.add(MTF("n", "1 + q_c"))
    g.add(C("c", 0.5))
    g.connect("Q", "n")
    g.connect("n", "c")
    with pytest.raises(DerivationError, match="c"):
        g.equations()


def test_fields_energy_gradient_is_reciprocal():
    g = BondGraph("field")
    g.add(Sf("v1"))
    g.add(Sf("v2"))
    g.add(CField("spring2", ["a", "b"], energy="ka*q_a**2/2 + kb*q_b**2/2 + kab*q_a*q_b",
                 params={"ka": 3.0, "kb": 5.0, "kab": 1.0}))
    g.connect("v1", ("spring2", "a"))
    g.connect("v2", ("spring2", "b"))
    g.add_output("Fa", "e_bond1")
    g.add_output("Fb", "e_bond2")
    eqs = g.equations()
    qa, qb, ka, kb, kab = map(S, "q_spring2_a q_spring2_b ka kb kab".split())
    assert_same(eqs.f, [S("v1"), S("v2")])
    assert_same(eqs.h, [ka * qa + kab * qb, kb * qb + kab * qa])


def test_ifield():
    g = BondGraph("ifield")
    g.add(Se("F1"))
    g.add(Se("F2"))
    g.add(IField("masses", ["x", "y"], laws={"x": "p_x/m + p_y/mc", "y": "p_y/m + p_x/mc"},
                 params={"m": 2.0, "mc": 10.0}))
    g.connect("F1", ("masses", "x"))
    g.connect("F2", ("masses", "y"))
    eqs = g.equations()
    assert_same(eqs.f, [S("F1"), S("F2")])
    assert eqs.state_names == ("p_masses_x", "p_masses_y")


def test_equation_element_pneumatic_chamber():
    """A pseudo-bond element: pressure / mass-flow port and force / velocity port."""
    g = BondGraph("chamber")
    g.add(MSf("valve", "kv*(Ps - P)", params={"kv": 1e-8, "Ps": 6e5}))
    g.add(EquationElement(
        "cyl", ports={"pn": "in", "mech": "out"},
        outputs={"e_pn": "P", "e_mech": "(P - Pa)*Ap"},
        states={"P": "kappa*Rg*T*f_pn/(Ap*x) - kappa*P*f_mech/x", "x": "f_mech"},
        initial={"P": 1e5, "x": 0.05}, units={"P": "Pa", "x": "m"},
        params={"kappa": 1.4, "Rg": 287.0, "T": 293.0, "Ap": 1e-3, "Pa": 1e5}))
    g.connect("valve", ("cyl", "pn"))
    g.add(One("v"))
    g.connect(("cyl", "mech"), "v")
    g.add(I("mp", 0.5))
    g.connect("v", "mp")
    eqs = g.equations()
    P, x, p, kv, Ps, kappa, Rg, T, Ap, Pa, mp = map(S, "P x p_mp kv Ps kappa Rg T Ap Pa mp".split())
    mdot, v = kv * (Ps - P), p / mp
    assert eqs.state_names == ("P", "x", "p_mp")
    assert_same(eqs.f, [kappa * Rg * T * mdot / (Ap * x) - kappa * P * v / x, v, (P - Pa) * Ap])
    assert eqs.units["P"] == "Pa"


def test_held_variables_and_fixed_step():
    g = BondGraph("sampled")
    g.add(EquationElement("fric", ports={"p": "in"}, outputs={"e_p": "Tf"},
                          held={"Tf": "mu*sign(f_p)*(1 + h_step)"}, fixed_step=1e-3,
                          params={"mu": 0.2}))
    g.add(One("j"))
    g.add(Se("tau"))
    g.add(I("J", 0.1))
    g.connect("tau", "j")
    g.connect("j", "fric")
    g.connect("j", "J")
    eqs = g.equations()
    assert eqs.fixed_step == 1e-3 and not eqs.is_smooth
    assert eqs.held_names == ("Tf",)
    mu, p, J = S("mu"), S("p_J"), S("J")
    h = sp.Symbol("h_step", real=True)
    assert_same(eqs.f, [S("tau") - S("Tf")])
    assert sp.simplify(eqs.held_update[0] - mu * sp.sign(p / J) * (1 + h)) == 0


def test_pretty_and_latex_name_everything():
    eqs = library.build("dc-motor").equations()
    text = eqs.pretty()
    for name in ("dp_La/dt", "dp_Jm/dt", "w_L", "km = 0.05 N m/A", "[rad/s]"):
        assert name in text
    tex = eqs.latex()
    assert tex.startswith("\\begin{aligned}") and r"\dot{p_{La}}" in tex


def test_equations_are_cached_until_the_graph_changes():
    g = library.build("rlc")
    first = g.equations()
    assert g.equations() is first
    g.add_output("vR", "e_Rs")
    assert g.equations() is not first and "vR" in g.equations().outputs


@pytest.mark.parametrize("name", library.names())
def test_every_builtin_model_derives(name):
    eqs = library.build(name).equations()
    assert len(eqs.f) == len(eqs.states)
    assert all(isinstance(e, sp.Expr) for e in eqs.f + eqs.h)
