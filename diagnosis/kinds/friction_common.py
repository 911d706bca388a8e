"""What the friction kinds at a 1-junction share: the smoothing flow of the sign, the level
parameter and its starts, the units, and the R element with a friction law.

The sign of the flow is smoothed, :math:`\\tanh(f / v_\\varepsilon)`, so the model stays smooth
(variable-step integration, Model-Exchange FMU); :math:`v_\\varepsilon` is fixed (not fitted) at
1 % of the RMS flow of the nominal simulation at the junction, so the friction reaches 76 % of its
level at 1 % of the typical speed.  A dry friction is a sign: the smoothing is numerical, and it
is kept as small as the integrators afford.  At 5 % the smoothed law was a visibly different
curve: near rest it acts as a damper of slope :math:`F_c/v_\\varepsilon`, and a sharp Coulomb
friction then fitted better as a stiff Dahl hysteresis, a Stribeck peak worse than no friction
at all.  The slope at rest this sharpness costs is a real decaying mode, which the ROS2 path
(:mod:`bondgraph.numerics.evaluate_stiff`) steps over.
"""
from __future__ import annotations

from bondgraph import R

from ..catalogue_common import ParamSpec, fresh_name, junction_domain, junction_units
from .base import Proposal, hang

__all__ = ["V_EPS_FRACTION", "smoothing_flow", "namer", "level", "viscous", "with_level_starts",
           "friction_r", "displacement_unit"]

#: smoothing velocity of the sign, as a fraction of the RMS junction flow
V_EPS_FRACTION = 0.01


def namer(site):
    """A fresh parameter name ``<base>_<junction>``."""
    return lambda base: fresh_name(site.taken, f"{base}_{site.name}")


def smoothing_flow(site) -> tuple:
    """The constant ``(name, value, unit, description)`` of the smoothing flow at `site`."""
    _, f_unit = junction_units(site.graph, site.name)
    return (namer(site)("v_eps"), V_EPS_FRACTION * site.scales.flow, f_unit,
            f"smoothing flow of the friction sign at {site.name}")


def level(site, base: str, what: str) -> ParamSpec:
    """A friction level: 10 % of the junction's effort scale, up to 10 times it."""
    e_unit, _ = junction_units(site.graph, site.name)
    E = site.scales.effort
    return ParamSpec(namer(site)(base), 0.1 * E, 0.0, 10 * E, e_unit, what)


def viscous(site) -> ParamSpec:
    """The viscous friction coefficient at `site`."""
    e_unit, f_unit = junction_units(site.graph, site.name)
    E, V = site.scales.effort, site.scales.flow
    b_unit = f"{e_unit} s/m" if f_unit == "m/s" else (f"{e_unit}/({f_unit})" if f_unit else "")
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
    """The smoothed sign of the flow, with the candidate's smoothing-flow constant."""
    return f"tanh(f/{cand.constants[0][0]})"


def displacement_unit(f_unit: str) -> str:
    """The unit of the integral of a flow."""
    return {"m/s": "m", "rad/s": "rad", "m^3/s": "m^3", "A": "C", "kg/s": "kg"}.get(f_unit, "1")
