"""Antagonistic pneumatic-artificial-muscle (PAM) joint as a pseudo-bond graph ([1]_).

Two proportional valves fill and exhaust two McKibben muscles that pull on
the two ends of a seesaw.  The pneumatic side is a pseudo-bond graph
(effort: absolute pressure, Pa; flow: mass flow, kg/s, positive INTO the
muscle); the mechanical side is a rotational bond graph (torque, N m /
angular velocity, rad/s).  Every reading of the paper that it leaves open
follows ``docs/pam-conventions.md``, the project's reference conventions.

Structure (full variant)::

    MSf:valve1 -> 0:chamber1 -> PneumaticC:muscle1 [pn | mech] <- MTF:arm1 (dl1/dpsi = -r cos psi) <- 1:seesaw
    MSf:valve2 -> 0:chamber2 -> PneumaticC:muscle2 [pn | mech] <- MTF:arm2 (dl2/dpsi = +r cos psi) <- 1:seesaw
    1:seesaw -> I:J, C:k_s (state q_psi = psi), Eq:friction (held T_f)

* ``valve<i>`` (MSf, eq. (5)): ``m = A0 (alpha m_in - (1 - alpha) m_out)``
  with ``alpha = kappa(u_i)``, the conventions' piecewise-linear table, and
  the standard compressible-orifice flux per unit area (choked below the
  critical pressure ratio), signed so that a reversed pressure difference
  reverses the flow; ``A0 = A1`` when the net flux is positive, ``A2``
  otherwise.
* ``chamber<i>`` 0-junction: the chamber's mass balance (common effort: the
  pressure ``P_<i>``); a leak or any other flow out of the chamber is a
  bond on it.
* ``muscle<i>`` (:class:`~bondgraph.elements.PneumaticChamber`, a two-port
  pneumatic C-field): state ``P_<i>`` with eq. (4)
  :math:`\\dot P = k_1 R T m / V - k_2 (\\dot V / V) P`, volume eq. (3)
  :math:`V = D_1 l^2 + D_2 l + D_3` of the length eq. (2)
  :math:`l_{1,2} = L_0 \\mp r \\sin\\psi`.  Its port ``pn`` receives the
  mass flow and sets the pressure; its port ``mech`` (natural direction in)
  receives the elongation rate :math:`\\dot l` (minus the contraction
  velocity) and sets the contraction force eqs. (6)-(7)
  :math:`F = (p_{v1} l + p_{v2}) P + p_{w1} l + p_{w2}` (Table II, last
  index = muscle).  Hence :math:`\\dot V = (2 D_1 l + D_2) \\dot l`.
* ``arm<i>`` (MTF, modulus :math:`\\partial l_i/\\partial\\psi`): with the
  bonds drawn seesaw -> arm -> muscle, :math:`\\dot l_i = m \\dot\\psi`
  and the torque taken from the seesaw is :math:`m F_i`, so the seesaw
  receives :math:`\\tau = r\\cos\\psi (F_1 - F_2)`, eq. (9).
* ``seesaw`` 1-junction: ``J`` (state ``p_J``, :math:`\\dot\\psi = p_J/J`),
  ``k_s`` (state ``q_psi`` = :math:`\\psi`) and ``friction``, so
  :math:`J\\ddot\\psi = \\tau - T_f - k_s\\psi`, eq. (8).
* ``friction`` (equation element, held ``T_f``, ``fixed_step`` 0.25 ms):
  Kikuuwe's law eq. (10) with :math:`Z = h/J`, evaluated at the start of
  each integration sub-step and held over it.

Variants: ``"frictionless"`` omits the friction element (a smooth model);
``"locked"`` replaces ``J``, ``k_s`` and the friction by an MSf of zero
velocity on the seesaw junction (:math:`\\psi \\equiv 0`), the paper's torque
tests.  Outputs (eq. (11b)): ``psi`` (deg), ``P1``, ``P2`` (Pa, absolute),
``tau`` (N m).  Inputs ``u1``, ``u2`` (V, clipped to [0, 10] in the valve law).

The conventions' fixed-step scheme (1 ms samples, 4 classic RK4 sub-steps of
0.25 ms, friction held per sub-step, inputs held per sample) is what
``simulate(pam(), (0, T), inputs=..., output_interval=1e-3)`` does.

References
----------
.. [1] T. Shin, T. Ibayashi, K. Kogiso, "Detailed dynamic model of antagonistic
   PAM system and its experimental validation", seed 000 (``docs/references.md``):
   eqs. (2)-(11), Table II.
"""
from __future__ import annotations

from types import MappingProxyType
from typing import Literal, Mapping

from bondgraph.elements import C, EquationElement, I, MSf, MTF, One, PneumaticChamber, Zero
from bondgraph.graph import BondGraph
from bondgraph.guards import Guard
from bondgraph.params import Param, values_with_overrides
from ..errors import ArgumentError

__all__ = ["pam", "PARAMETERS", "KAPPA_KNOTS", "FRICTION_STEP", "DP_CLAMP", "parameter_values",
           "kappa_law", "orifice_flux_law", "valve_law", "valve_locals", "VALVE_FLOW"]

#: Sub-step of the friction law and of the conventions' RK4 scheme, s (4 per 1 ms sample).
FRICTION_STEP = 0.25e-3
#: Lower clamp of ``P_i - P_out`` in T_p, Pa (conventions: T_p diverges at atmospheric pressure).
DP_CLAMP = 20e3
#: (u in V, alpha): the conventions' knots of kappa(u), piecewise linear between them.
KAPPA_KNOTS = tuple(zip(
    [0.5 * j for j in range(21)],
    (0.0, 0.1378, 0.1828, 0.2134, 0.2390, 0.2631, 0.2856, 0.3069, 0.3269, 0.3458, 0.3645,
     0.3844, 0.4057, 0.4288, 0.4545, 0.4835, 0.5174, 0.5589, 0.6134, 0.6962, 1.0)))

_NMS = "N m s/rad"
PARAMETERS: Mapping[str, Param] = MappingProxyType({p.name: p for p in (
    Param("r_p", 0.006, "m", "shaft radius r_p; Table II"),
    Param("r", 0.0365, "m", "seesaw radius r (muscle lever arm); Table II"),
    Param("L0", 0.165, "m", "muscle length L_0 at psi = 0; Table II"),
    Param("M", 0.256, "kg", "seesaw mass M; Table II"),
    Param("g", 9.80, "m/s^2", "gravitational acceleration g; Table II"),
    Param("P_tank", 0.7100e6, "Pa", "supply (tank) absolute pressure P_tank; Table II"),
    Param("P_out", 0.1013e6, "Pa", "atmospheric (exhaust) absolute pressure P_out; Table II"),
    Param("k", 1.40, "1", "specific heat ratio of air k; Table II"),
    Param("R", 287.0, "J/(kg K)", "gas constant of air R; Table II"),
    Param("T", 293.0, "K", "air temperature T; Table II"),
    Param("J", 4.263e-4, "kg m^2", "seesaw moment of inertia J; Table II"),
    Param("k_s", 4.117e-4, "N m/rad", "seesaw static torque coefficient k_s; Table II"),
    Param("c_s", 2.256e-3, _NMS, "viscous friction coefficient c_s; Table II (printed unit N s, "
                                 "rotational: N m s/rad)"),
    Param("k1", 1.100, "1", "polytropic index k_1 of the flow term, eq. (4); Table II"),
    Param("k2", 0.4545, "1", "polytropic index k_2 of the volume term, eq. (4); Table II"),
    Param("D1", -2.440e-2, "m", "volume polynomial D_1, eq. (3); Table II"),
    Param("D2", 6.824e-3, "m^2", "volume polynomial D_2, eq. (3); Table II"),
    Param("D3", -4.254e-4, "m^3", "volume polynomial D_3, eq. (3); Table II"),
    Param("p_v11", 7.045e-3, "m", "force slope v = p_v1 l + p_v2, p_v1 of muscle 1, eq. (7a); Table II"),
    Param("p_v21", -1.017e-3, "m^2", "force slope p_v2 of muscle 1, eq. (7a); Table II"),
    Param("p_w11", -5.568e2, "N/m", "force intercept w = p_w1 l + p_w2, p_w1 of muscle 1, eq. (7b); Table II"),
    Param("p_w21", 72.86, "N", "force intercept p_w2 of muscle 1, eq. (7b); Table II"),
    Param("p_v12", 6.423e-3, "m", "force slope p_v1 of muscle 2, eq. (7a); Table II"),
    Param("p_v22", -9.184e-4, "m^2", "force slope p_v2 of muscle 2, eq. (7a); Table II"),
    Param("p_w12", -197.8, "N/m", "force intercept p_w1 of muscle 2, eq. (7b); Table II"),
    Param("p_w22", -15.75, "N", "force intercept p_w2 of muscle 2, eq. (7b); Table II"),
    Param("A1", 5.184e-8, "m^2", "valve filling orifice area (Table II A_11), both valves"),
    Param("A2", 7.776e-8, "m^2", "valve exhaust orifice area (Table II A_12), both valves"),
    Param("mu_p", 4e8, "N m Pa^2", "tube Coulomb friction coefficient mu_p (Table II T'_p)"),
    Param("mu_s", 0.2, "1", "shaft Coulomb friction coefficient mu_s; Table II"),
)})
"""Table II of [1]_ by name (SI), with unit and description.

The units of ``p_v*``, ``p_w*`` and ``mu_p`` are those that make eqs. (6),
(7) and T_p dimensionally consistent (Table II prints "-").
"""

_MECHANICAL = ("J", "k_s")
_FRICTION = ("c_s", "mu_p", "mu_s", "r_p", "M", "g")
Variant = Literal["full", "frictionless", "locked"]
_GRAPH_NAMES = {"full": "pam", "frictionless": "pam_frictionless", "locked": "pam_locked"}


def parameter_values(overrides: Mapping[str, float] | None = None) -> dict[str, float]:
    """Table II values by name (SI), `overrides` applied.

    Raises
    ------
    ParameterError
        An override names no parameter (the message lists the known ones) or is not finite.
    """
    return values_with_overrides(PARAMETERS, overrides, owner="pam")


# -- constitutive laws, as expression text over the graph's names -------------------------

def kappa_law(u: str, *, clipped: bool = False) -> str:
    """Open rate :math:`\\alpha = \\kappa(u)` as a Piecewise of linear segments.

    `u` (V) is clipped to [0, 10] first (unless `clipped` says it already
    is); between the knots of :data:`KAPPA_KNOTS` (conventions' table) alpha
    is linear in u.
    """
    uc = u if clipped else f"Min(Max({u}, 0), 10)"
    pieces = []
    for (ua, aa), (ub, ab) in zip(KAPPA_KNOTS, KAPPA_KNOTS[1:]):
        # alpha = slope u + intercept; the knots are short decimals, so are these (round
        # away the float noise of the division: 0.09, not 0.08999999999999997)
        slope = round((ab - aa) / (ub - ua), 10)
        intercept = round(aa - slope * ua, 10)
        cond = "True" if ub == KAPPA_KNOTS[-1][0] else f"{uc} <= {ub!r}"
        pieces.append(f"({slope!r}*{uc} + {intercept!r}, {cond})")
    return f"Piecewise({', '.join(pieces)})"


def orifice_flux_law(p_a: str, p_b: str) -> str:
    """Signed mass flux per unit orifice area from `p_a` to `p_b` (kg/(s m^2)).

    Standard compressible-orifice law (conventions, eq. (5) of [1]_ with the
    exponents corrected), with :math:`P_u = \\max(p_a, p_b)`,
    :math:`x = \\min(p_a, p_b)/P_u`, :math:`b = (2/(k+1))^{k/(k-1)}`:

    .. math::

        \\Phi = \\frac{P_u}{\\sqrt{T}}
        \\begin{cases} \\sqrt{k/R}\\,(2/(k+1))^{(k+1)/(2(k-1))} & x \\le b \\\\
        \\sqrt{2k/(R(k-1))}\\; x^{1/k} \\sqrt{1 - x^{(k-1)/k}} & x > b \\end{cases}

    times :math:`\\mathrm{sgn}(p_a - p_b)`: a reversed pressure difference
    reverses the flow with the same law, and no branch ever takes the root
    of a negative number.
    """
    pu, pd = f"Max({p_a}, {p_b})", f"Min({p_a}, {p_b})"
    x = f"({pd}/{pu})"
    choked = "sqrt(k/R)*(2/(k + 1))**((k + 1)/(2*(k - 1)))"
    unchoked = f"sqrt(2*k/(R*(k - 1)))*{x}**(1/k)*sqrt(1 - {x}**((k - 1)/k))"
    critical = "(2/(k + 1))**(k/(k - 1))"
    return (f"sign({p_a} - {p_b})*{pu}/sqrt(T)*"
            f"Piecewise(({choked}, {x} <= {critical}), ({unchoked}, True))")


def valve_law(u: str, p: str) -> str:
    """Mass flow into the muscle, eq. (5): :math:`m = A_0 (\\alpha m_{in} - (1-\\alpha) m_{out})`.

    `u` is the valve voltage (V), `p` the muscle pressure (Pa, absolute);
    :math:`m_{in}` is the flux tank -> muscle, :math:`m_{out}` muscle ->
    atmosphere (both per unit area, signed); :math:`A_0 = A_1` if the net
    flux is positive, :math:`A_2` otherwise (conventions).
    """
    alpha = f"({kappa_law(u)})"
    net = (f"({alpha}*{orifice_flux_law('P_tank', p)} - "
           f"(1 - {alpha})*{orifice_flux_law(p, 'P_out')})")
    # A1 net if net > 0, A2 net otherwise, without a Piecewise on a Piecewise (sympy
    # would fold the nested conditions into a very deep expression)
    return f"((A1 + A2)/2*{net} + (A1 - A2)/2*Abs({net}))"


def valve_locals(u: str, p: str) -> dict[str, str]:
    """The valve law :func:`valve_law` as named locals, in evaluation order.

    ``u_c`` (clipped voltage, V), ``alpha`` (open rate), ``m_in`` and
    ``m_out`` (signed fluxes per unit area tank -> muscle and muscle ->
    atmosphere, kg/(s m^2)) and ``net``; the valve's mass flow is then
    :data:`VALVE_FLOW` over these names.
    """
    return {"u_c": f"Min(Max({u}, 0), 10)", "alpha": kappa_law("u_c", clipped=True),
            "m_in": orifice_flux_law("P_tank", p), "m_out": orifice_flux_law(p, "P_out"),
            "net": "alpha*m_in - (1 - alpha)*m_out"}


#: Mass flow into the muscle over :func:`valve_locals`' names, eq. (5) (A1 if net > 0, else A2).
VALVE_FLOW = "(A1 + A2)/2*net + (A1 - A2)/2*Abs(net)"


def _length(i: int, psi: str) -> str:
    """Muscle length eq. (2) (conventions): l1 = L0 - r sin psi, l2 = L0 + r sin psi."""
    return f"(L0 {'-' if i == 1 else '+'} r*sin({psi}))"


def _force(i: int, psi: str) -> str:
    """Contraction force eqs. (6)-(7): F = (p_v1 l + p_v2) P + p_w1 l + p_w2."""
    l = _length(i, psi)
    return f"((p_v1{i}*{l} + p_v2{i})*P_{i} + p_w1{i}*{l} + p_w2{i})"


def _torque(psi: str) -> str:
    """Joint torque eq. (9): tau = r cos psi (F1 - F2)."""
    return f"(r*cos({psi})*({_force(1, psi)} - {_force(2, psi)}))"


def _muscle(i: int, psi: str) -> PneumaticChamber:
    volume = f"(D1*{_length(i, psi)}**2 + D2*{_length(i, psi)} + D3)"   # guards see graph names, not locals
    guards = [Guard(f"V_{i}", volume, min=0.0, unit="m^3",
                    description=f"chamber volume of muscle {i}, eq. (3)"),
              Guard(f"P_{i}_abs", f"P_{i}", min=0.0, unit="Pa",
                    description=f"absolute pressure in muscle {i}")]
    # a two-port pneumatic C-field: chamber eq. (4) on length eq. (2), volume eq. (3), force eqs. (6)-(7)
    return PneumaticChamber(
        f"muscle{i}", pressure=f"P_{i}", length=_length(i, psi), volume="D1*l**2 + D2*l + D3",
        force=f"(p_v1{i}*l + p_v2{i})*P_{i} + p_w1{i}*l + p_w2{i}", flow_index="k1", volume_index="k2",
        initial_pressure=PARAMETERS["P_out"].value, guards=guards,
        description=f"muscle {i}: chamber eq. (4), volume eq. (3), contraction force eqs. (6)-(7); "
                    "port pn: pressure / mass flow in, port mech: force / elongation rate")


def _friction() -> EquationElement:
    """Kikuuwe friction eq. (10) (conventions: Z = h/J, T_s, T_p with the clamp)."""
    z = "(h_step/J)"
    law = (f"Piecewise(((F_c*sign(w) + c_s*w)/(1 + {z}*c_s), Abs(w) > {z}*F_c), "
           f"(w/{z}, True))")
    named = {
        "F_1": _force(1, "q_psi"), "F_2": _force(2, "q_psi"),
        # velocity predictor: every torque on the seesaw but friction is e_J + T_f (J's effort
        # with the held friction added back), so an effort attached to the seesaw later (a load,
        # another friction) is in it too; for this graph it is r cos(psi) (F_1 - F_2) - k_s psi
        "w": f"f_shaft + {z}*(e_J + T_f)",
        "T_s": "r_p*mu_s*Abs(F_1 + F_2 - M*g)",                          # shaft Coulomb
        "T_p": f"mu_p*(1/Max(P_1 - P_out, {DP_CLAMP!r})**2 + 1/Max(P_2 - P_out, {DP_CLAMP!r})**2)",
        "F_c": "T_s + T_p",
    }
    return EquationElement(
        "friction", ports={"shaft": "in"}, outputs={"e_shaft": "T_f"}, locals=named,
        held={"T_f": law}, fixed_step=FRICTION_STEP, units={"T_f": "N m"},
        descriptions={"T_f": "Kikuuwe friction torque eq. (10), held over each sub-step"},
        description="joint friction (Kikuuwe, eq. (10)): shaft T_s + tube T_p Coulomb, viscous c_s")


def pam(variant: Variant = "full", *, params: Mapping[str, float] | None = None) -> BondGraph:
    """The antagonistic PAM joint of [1]_ as a pseudo-bond graph.

    Parameters
    ----------
    variant : {"full", "frictionless", "locked"}
        ``"full"``: Kikuuwe friction as a held variable (fixed-step RK4,
        0.25 ms sub-steps); ``"frictionless"``: :math:`T_f \\equiv 0`, a smooth
        model; ``"locked"``: :math:`\\psi \\equiv \\dot\\psi \\equiv 0`
        (zero-velocity source on the seesaw junction).
    params : mapping str -> float, optional
        Values (SI) overriding :data:`PARAMETERS`.

    Returns
    -------
    BondGraph
        Named ``"pam"``, ``"pam_frictionless"`` or ``"pam_locked"``.  States
        ``q_psi`` (psi, rad), ``p_J`` (J psi', N m s; not in ``"locked"``),
        ``P_1``, ``P_2`` (Pa, absolute); held ``T_f`` (N m, ``"full"``
        only); inputs ``u1``, ``u2`` (V); outputs ``psi`` (deg), ``P1``,
        ``P2`` (Pa, absolute), ``tau`` (N m, eq. (11b)).  Initial state:
        :math:`\\psi = \\dot\\psi = 0`, :math:`P_1 = P_2 = P_{out}`, the
        equilibrium of the valves at u = 0 (alpha = 0: the muscles vent to
        the atmosphere).

    Raises
    ------
    ValueError
        An unknown `variant`.
    ParameterError
        An unknown name in `params`.

    Examples
    --------
    >>> g = pam("locked")
    >>> g.equations().state_names
    ('P_1', 'P_2')
    """
    if variant not in _GRAPH_NAMES:
        raise ArgumentError(f"pam: variant must be one of {', '.join(map(repr, _GRAPH_NAMES))}; "
                         f"found {variant!r}")
    values = parameter_values(params)
    g = BondGraph(_GRAPH_NAMES[variant], description=f"antagonistic PAM joint, seed 000 ({variant})")
    locked = variant == "locked"
    used = [n for n in PARAMETERS if n not in _MECHANICAL
            and (variant == "full" or n not in _FRICTION)]

    def p(name: str) -> Param:
        base = PARAMETERS[name]
        return Param(name, values[name], base.unit, base.description)

    for name in used:
        g.add_parameter(p(name))
    for i in (1, 2):
        g.add_input(f"u{i}", unit="V", description=f"valve {i} voltage (clipped to [0, 10] V)")
    psi = "0" if locked else "q_psi"
    g.add(One("seesaw", description="joint angular velocity psi'"))
    for i in (1, 2):
        g.add(MSf(f"valve{i}", VALVE_FLOW, locals=valve_locals(f"u{i}", f"P_{i}"), domain="pneumatic",
                  description=f"valve {i}, eq. (5): mass flow into muscle {i}"))
        g.add(Zero(f"chamber{i}", description=f"mass balance of muscle {i}'s chamber (common pressure P_{i})"))
        g.add(_muscle(i, psi))
        g.add(MTF(f"arm{i}", f"{'-' if i == 1 else ''}r*cos({psi})",
                  description=f"lever of muscle {i}: dl{i}/dpsi (eq. (2)); torque eq. (9)"))
        g.connect(f"valve{i}", f"chamber{i}")
        g.connect(f"chamber{i}", (f"muscle{i}", "pn"))
        g.connect("seesaw", f"arm{i}")
        g.connect(f"arm{i}", (f"muscle{i}", "mech"))
    if locked:
        g.add(MSf("lock", "0", domain="rotation", description="joint held at psi = 0"))
        g.connect("lock", "seesaw")
    else:
        g.add(I("J", p("J"), domain="rotation", description="seesaw inertia"))
        g.add(C("k_s", stiffness=p("k_s"), state="q_psi", domain="rotation",
                description="seesaw static torque k_s; displacement q_psi = psi"))
        g.connect("seesaw", "J")
        g.connect("seesaw", "k_s")
        if variant == "full":
            g.add(_friction())
            g.connect("seesaw", ("friction", "shaft"))
    g.add_output("psi", f"{psi}*180/pi", unit="deg", description="joint angle, eq. (11b)")
    g.add_output("P1", "P_1", unit="Pa", description="muscle 1 absolute pressure, eq. (11b)")
    g.add_output("P2", "P_2", unit="Pa", description="muscle 2 absolute pressure, eq. (11b)")
    g.add_output("tau", _torque(psi), unit="N m", description="joint torque r cos(psi) (F1 - F2), eqs. (9), (11b)")
    return g
