"""What the friction kinds at a 1-junction share: the smoothing flow of the sign, the level
parameter and its starts, the units, and the R element with a friction law.

The sign of the flow is smoothed, :math:`\\tanh(f / v_\\varepsilon)`, so the model stays smooth
(variable-step integration, Model-Exchange FMU).  How blunt a real friction's reversal is (the
band of speed over which it builds up: presliding, a lubricant film, a compliant contact) is a
property of the rig, not of the integrator, so :math:`v_\\varepsilon` is fitted with the levels
(:func:`smoothing`, every sign kind's last parameter).  It is not priced in the choice of a model
(:attr:`~diagnosis.catalogue_common.ParamSpec.priced`): it shapes the sign and adds no physics.
It starts at 1 % of the RMS flow of the nominal simulation at the junction, where the friction
reaches 76 % of its level at 1 % of the typical speed, or at the smoothing the feature regression
chose (:func:`sharpened`: 1/3, 1, 3 and 10 %), and ranges over :data:`V_EPS_RANGE`, 0.25-20 %.
Fixed at 1 %, a blunter truth left a systematic error near every reversal that a Dahl element or
a small viscous term absorbed, and the held-out samples then resolved the richer law (a Coulomb
friction smoothed over about 10 % of the speed read as Coulomb + viscous friction,
``tests/test_diagnosis_segments.py``).  At 20 % the law still reaches its level within the
typical speed (:math:`\\tanh 5`), a dry friction that a viscous law cannot pass for.  The slope
at rest a sharp sign costs is a real decaying mode, which the linearly implicit Rosenbrock path
(:mod:`bondgraph.numerics.evaluate_stiff`) steps over.
"""
from __future__ import annotations

from bondgraph import R
from bondgraph.params import DOMAINS

from ..catalogue_common import ParamSpec, fresh_name, junction_domain, junction_units
from .base import Proposal, hang

__all__ = ["V_EPS_FRACTION", "V_EPS_RANGE", "SHARPNESS_GRID", "smoothing", "sharpened", "namer", "level", "viscous",
           "with_level_starts", "friction_r", "sign", "displacement_unit"]

#: smoothing velocity of the sign, as a fraction of the RMS junction flow
V_EPS_FRACTION = 0.01
#: the smoothing velocities the features try, as fractions of the RMS flow
SHARPNESS_GRID = (V_EPS_FRACTION / 3, V_EPS_FRACTION, 3 * V_EPS_FRACTION, 10 * V_EPS_FRACTION)
#: the range of the fitted smoothing velocity, as fractions of the RMS flow
V_EPS_RANGE = (V_EPS_FRACTION / 4, 20 * V_EPS_FRACTION)


def namer(site):
    """A fresh parameter name ``<base>_<junction>``."""
    return lambda base: fresh_name(site.taken, f"{base}_{site.name}")


def smoothing(site) -> ParamSpec:
    """The smoothing flow of the sign at `site`, fitted (not priced): from :data:`V_EPS_FRACTION`
    of the junction's RMS flow, within :data:`V_EPS_RANGE` of it."""
    _, f_unit = junction_units(site.graph, site.name)
    V = site.scales.flow
    return ParamSpec(namer(site)("v_eps"), V_EPS_FRACTION * V, V_EPS_RANGE[0] * V, V_EPS_RANGE[1] * V,
                     f_unit, f"smoothing flow of the friction sign at {site.name}", priced=False)


def sharpened(s, groups_at) -> list:
    """The feature groups `groups_at(sign)` (a list of :class:`FeatureGroup` given the smoothed
    sign of the flow) once per smoothing of :data:`SHARPNESS_GRID`, each group's grid extended by
    its smoothing flow (the candidate's last parameter, :func:`smoothing`)."""
    out = []
    for fraction in SHARPNESS_GRID:
        v_eps = float(fraction * s.v_rms)
        for g in groups_at(s.sign_at(fraction)):
            detail = ", ".join(x for x in (g.detail, f"v_eps = {v_eps:.3g}") if x)
            out.append(g._replace(detail=detail, grid=tuple(g.grid) + (v_eps,)))
    return out


def level(site, base: str, what: str) -> ParamSpec:
    """A friction level: 10 % of the junction's effort scale, up to 10 times it."""
    e_unit, _ = junction_units(site.graph, site.name)
    E = site.scales.effort
    return ParamSpec(namer(site)(base), 0.1 * E, 0.0, 10 * E, e_unit, what)


def viscous(site) -> ParamSpec:
    """The viscous friction coefficient at `site`, in its domain's unit of resistance (an Ohm, not
    a V/(A))."""
    e_unit, f_unit = junction_units(site.graph, site.name)
    E, V = site.scales.effort, site.scales.flow
    b_unit = DOMAINS[junction_domain(site.graph, site.name)].resistance or (
        f"{e_unit} s/m" if f_unit == "m/s" else (f"{e_unit}/({f_unit})" if f_unit else ""))
    return ParamSpec(namer(site)("b_visc"), 0.1 * E / V, 0.0, 100 * E / V, b_unit,
                     f"viscous friction coefficient at {site.name}")


def with_level_starts(params, **fields) -> Proposal:
    """A proposal whose first parameter (the friction level, which may be far from 10 % of the
    effort scale) also starts at 0.1 and 5 times its guess."""
    first = params[0]
    starts = tuple({first.name: f * first.guess} for f in (0.1, 5.0) if f * first.guess <= first.upper)
    return Proposal(tuple(params), starts=starts, **fields)


def friction_r(graph, cand, law: str):
    """`graph` with an R ``<kind>_<junction>`` of effort `law` (in the flow ``f``) on the junction."""
    j = cand.place.name
    element = R(f"{cand.kind}_{j}", effort=law, domain=junction_domain(graph, j),
                description=f"{cand.kind.replace('_', ' ')} at {j}")
    return hang(graph, element, j)


def sign(cand) -> str:
    """The smoothed sign of the flow, with the candidate's smoothing flow (its last parameter)."""
    return f"tanh(f/{cand.params[-1].name})"


def displacement_unit(f_unit: str) -> str:
    """The unit of the integral of a flow."""
    return {"m/s": "m", "rad/s": "rad", "m^3/s": "m^3", "A": "C", "kg/s": "kg"}.get(f_unit, "1")
