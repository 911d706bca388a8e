"""``modulated_friction``: a Coulomb friction at a 1-junction whose level is set by another signal.

A magnetorheological damper's yield force follows its coil current, a seal's friction the
pressure that presses it, a brake's the command to its actuator; the signal reaches the friction
through a first-order lag (the coil's inductance, the seal's deformation).  The law, an equation
element on the junction with the lagged signal :math:`s_\\ell` as its state:

.. math::

    e = \\bigl(F_0 + k\\,(s_\\ell - s_{ref})\\bigr) \\tanh(f / v_\\varepsilon), \\qquad
    \\dot s_\\ell = (s - s_\\ell) / \\tau,

with :math:`s` one candidate signal (:func:`modulating_signals`): a model input (recorded, such
as a coil voltage or a valve command), or the effort of a C element of another domain that the
regime variables list (a temperature, a charge's voltage).  Pressures without a lag are
``pressure_dependent_friction``.  :math:`s_{ref}` (fixed) is the signal's mean in the nominal
simulation, so :math:`F_0` is the level at the mean signal; :math:`v_\\varepsilon` is that of the
other friction kinds.  Fitted: :math:`F_0`, :math:`k` and :math:`\\tau`; the lag state starts at
the signal's first value.  The Bingham model of an MR damper (Spencer et al., "Phenomenological
model of a magnetorheological damper", J. Eng. Mech. 123(3), 1997, eq. 1, with the yield force
linear in the filtered voltage, their eq. 7) is this law plus a viscous term, which
``viscous_friction`` adds in a further round.
"""
from __future__ import annotations

import numpy as np

from bondgraph import EquationElement
from bondgraph.elements import SOURCE_KINDS
from bondgraph.editing_inputs import expression_fields, mentions

from ..catalogue_common import ParamSpec, fresh_name, junction_domain, junction_elements, junction_units
from .base import Kind, Proposal, hang, register
from .feature_signals import FeatureGroup, lagged
from .friction_common import sharpened, smoothing

__all__ = ["ModulatedFriction", "modulating_signals"]

#: lag time constants the fit starts from, in sample intervals (the best of them, one batch)
_LAG_STARTS = (2.0, 20.0, 200.0)
#: other-domain C efforts offered at most (inputs are always offered)
_MAX_EFFORTS = 2


def modulating_signals(graph, junction: str, regime_variables=None) -> dict[str, str]:
    """Signals that may set a friction level at `junction`: label -> expression.

    Every input of the model except those that drive the junction itself (read by a source
    or an element bonded to it: the motion's cause, whose errors the actuator kinds
    describe), then the efforts ``e_<C>`` of C elements of another domain than the
    junction's, other than pressures (``pressure_dependent_friction``), that
    `regime_variables` lists (all of them without regime variables), at most two.
    """
    driving = _driving_inputs(graph, junction)
    out = {d.name: d.name for d in graph.inputs() if d.name not in driving}
    dom = junction_domain(graph, junction)
    efforts = [f"e_{e.name}" for e in graph.elements.values()
               if e.kind == "C" and getattr(e, "domain", dom) not in (dom, "pneumatic", "hydraulic", "generic")]
    if regime_variables:
        efforts = [e for e in efforts if e in regime_variables]
    out.update({e: e for e in efforts[:_MAX_EFFORTS]})
    return out


def _driving_inputs(graph, junction: str) -> set:
    """Inputs that drive `junction`: read by an element bonded to it (a source's own input, or
    an expression naming the input), or by a source of the junction's own domain anywhere (a
    force or torque of the same mechanics)."""
    names = {d.name for d in graph.inputs()}
    bonded = {e.name for e, _ in junction_elements(graph, junction)}
    dom = junction_domain(graph, junction)
    found = set()
    for element in graph.elements.values():
        entry = element.to_dict()
        source = entry.get("kind") in SOURCE_KINDS
        if not (entry["name"] in bonded or (source and entry.get("domain") == dom and dom != "generic")):
            continue
        if entry.get("kind") in ("Se", "Sf"):
            found.add(entry.get("input") or entry["name"])
        for container, key in expression_fields(entry):
            found |= {u for u in names if mentions(container[key], u)}
    return found & names


#: the modulating signal's lags the features try, in sample intervals
FEATURE_LAG_STEPS = (2.0, 20.0, 200.0)


@register
class ModulatedFriction(Kind):
    name = "modulated_friction"
    doors = ("1",)
    domains = ("translation", "rotation")
    feature_doors, feature_names, feature_price = "1", ("sign(v)", "(lag(m) - m_mean) sign(v)"), 3
    feature_signs = (1,)      # a friction takes energy (features.regress_kinds)
    nests = {"coulomb_friction": {0: 0, 3: 1}}
    # F0, k from the coefficients; the lag from the grid.  Guessed, a slope of the wrong size or a
    # lag decades off left the fit ten times above a pressure-dependent friction that needs neither,
    # and it was given up (diagnosis.fit_in_turn) while the features had found this law
    feature_params, feature_grid_params = 2, (2, 3)

    def features(self, s):
        """Sign, and the sign times each modulating signal through a lag of 2, 20 and 200
        sample intervals (at most a fifth of the record)."""
        lags = []
        for expr, m in s.labelled("signal").items():
            for n in FEATURE_LAG_STEPS:
                tau = min(max(n * s.dt, s.dt / 2), max(s.span / 5, s.dt))
                lags.append((expr, tau, lagged(m, s.t, tau)))
        return sharpened(s, lambda sign: [
            FeatureGroup(expr, f"lag {tau:.3g} s", ["sign(v)", "(lag(m) - m_mean) sign(v)"],
                         np.stack([sign, (lag - lag.mean()) * sign], axis=1), (float(tau),))
            for expr, tau, lag in lags])

    def propose(self, site):
        """One candidate per modulating signal that varies in the nominal simulation
        (``values["signal:<label>"]``; without data, every signal with unit scales)."""
        j, scales = site.name, site.scales
        e_unit, _ = junction_units(site.graph, j)
        E = scales.effort
        units = {d.name: d.unit for d in site.graph.inputs()}
        out = []
        for label, expr in modulating_signals(site.graph, j).items():   # those simulated: site.signals
            s = site.values.get(f"signal:{label}")
            if s is None and scales.from_data:
                continue                      # not simulated: nothing to scale it by
            if s is None:                     # listed without data: unit scales
                s = np.array([-1.0, 1.0])
            if not s.size or not float(s.std()) > 0:
                continue                      # a constant signal modulates nothing
            s_ref, s_scale, s_unit = float(s.mean()), float(s.std()), units.get(label, "")
            name = lambda base: fresh_name(site.taken, f"{base}_{j}_{label}")  # noqa: E731 - short local namer
            f0, k, tau = name("F0"), name("k_mod"), name("tau_mod")
            k_unit = f"{e_unit}/({s_unit})" if s_unit else e_unit
            tau_lo, tau_hi = scales.dt / 2, max(scales.span / 5, scales.dt)
            taus = [min(max(n * scales.dt, tau_lo), tau_hi) for n in _LAG_STARTS]
            out.append(Proposal(
                regime=expr,
                constants=((name("s_ref"), s_ref, s_unit, f"reference value of {label} for the friction at {j}"),
                           (name("s_0"), float(s[0]), s_unit, f"initial lagged value of {label} at {j}")),
                params=(ParamSpec(f0, 0.1 * E, 0.0, 10 * E, e_unit, f"friction level at {j} at the mean {label}"),
                        ParamSpec(k, 0.0, -10 * E / s_scale, 10 * E / s_scale, k_unit,
                                  f"change of the friction level at {j} per unit of {label}"),
                        ParamSpec(tau, taus[1], tau_lo, tau_hi, "s", f"lag of {label} reaching the friction at {j}"),
                        smoothing(site)),
                starts=tuple({f0: 0.1 * E * g,
                              k: sign * _slope_start(0.1 * E * g, 0.3 * E / s_scale, s, s_ref), tau: t}
                             for t in taus for sign in (1.0, -1.0) for g in (0.1, 1.0))))
        return out

    def build(self, graph, cand, values):
        """An equation element owning the lag state, on the 1-junction."""
        j = cand.place.name
        f0, k, tau, v_eps = (spec.name for spec in cand.params)
        (s_ref, *_), (_, start, *_) = cand.constants
        name = fresh_name(set(graph.elements), f"modulated_friction_{j}")
        state = f"s_lag_{name}"
        element = EquationElement(
            name, ports={"m": "in"}, outputs={"e_m": f"({f0} + {k}*({state} - {s_ref}))*tanh(f_m/{v_eps})"},
            states={state: f"(({cand.regime}) - {state})/{tau}"}, initial={state: start},
            units={state: cand.constants[0][2]},
            description=f"friction at {j} with its level set by {cand.regime} through a lag")
        return hang(graph, element, j)

    def explain(self, cand, values, show):
        j = cand.place.name
        f0, k, tau = (spec.name for spec in cand.params[:3])
        s_ref = cand.constants[0][1]
        slope = values.get(k, 0.0)
        trend = (f"{'more' if slope > 0 else 'less'} at higher {cand.regime} ({show(k)})" if slope
                 else f"whatever {cand.regime}")
        return (f"the motion at {j} loses about {show(f0)} whenever it moves (at {cand.regime} = {s_ref:.4g}), "
                f"{trend}, following {cand.regime} with a lag of {show(tau)}: "
                f"friction modulated by {cand.regime} at the {j} 1-junction")


def _slope_start(level: float, slope: float, s, s_ref: float) -> float:
    """The slope a start gives the level: `slope`, at most what keeps ``level + slope (s - s_ref)``
    at or above a tenth of `level` over the signal's recorded values `s`.  A friction's level is
    never negative, and a start that made it so over part of the record pushed the pam's seesaw
    on with the motion: runs of 500-1000 RK4 sub-steps a sample against 240 (10 s instead of 2.5 s
    each; seed 5757, case 043 spent most of its 27 minutes there) or a run away."""
    reach = float(np.max(np.abs(np.asarray(s, dtype=float) - s_ref)))
    return float(min(slope, 0.9 * level / reach)) if reach > 0 else float(slope)
