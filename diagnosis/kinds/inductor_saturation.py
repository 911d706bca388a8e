"""``inductor_saturation`` of an electrical I at a 1-junction: its iron core saturates, so the
current grows faster than the flux linkage :math:`\\lambda` (the I's momentum) beyond a knee.  The
law gets the second term of the two-term magnetising curve :math:`i = a\\lambda + b\\lambda^n`
common in transformer and ferroresonance studies, and the element's own inductance is refitted
with it,

.. math::

    i = \\Phi(\\lambda) \\left(1 + \\left|\\lambda / \\lambda_s\\right|^{n - 1}\\right)

(:math:`\\Phi(\\lambda) = \\lambda / L` for a linear inductor; a law-form inductor gets
:math:`\\Phi` plus a refitted linear term): :math:`\\lambda_s` the flux at which the core needs
twice the linear current, :math:`n` (odd in practice; here 3-11, continuous) how sharp its knee
is.  :math:`n = 3` is the first odd term of any smooth saturating curve, e.g.
:math:`\\lambda = L i_s \\arctan(i / i_s)` has :math:`\\lambda_s^2 = 3 L^2 i_s^2`.  A linear
inductance identified from data carries part of the saturation's average, hence the refit.  The
I-field dual of ``nonlinear_stiffness`` (a C's cubic law); a mass's or a pipe's inertance does not
saturate, so the kind is electrical only.

Its features, from the corrected run: with the nominal's flux :math:`\\lambda_n = L i`, matching
the saturated current needs the extra effort :math:`d = \\dot\\lambda_n - \\dot\\lambda
\\approx \\delta\\,\\dot\\lambda + (\\lambda_r / \\lambda_s)^{n-1}\\,\\mathrm{d}(\\lambda
|\\lambda / \\lambda_r|^{n-1})/\\mathrm{d}t` (:math:`\\delta = L / L' - 1`, :math:`\\lambda_r` the
RMS flux), for :math:`n` on a grid (:data:`FEATURE_EXPONENTS`).

"""
from __future__ import annotations

import numpy as np
import sympy as sp

from ..catalogue_common import ParamSpec, fresh_name
from .base import Kind, Proposal, register
from .feature_signals import FeatureGroup, rms
from .storage_common import inductors

#: the exponents n the features try (odd: a core's curve is odd in the flux)
FEATURE_EXPONENTS = (3, 5, 7, 9)


@register
class InductorSaturation(Kind):
    name = "inductor_saturation"
    doors = ("1",)
    domains = ("electrical",)
    feature_doors, feature_names, feature_price = "1", ("d(lambda |lambda/lambda_r|^(n-1))/dt", "d(lambda)/dt"), 2

    def features(self, s):
        """Per moving inductor flux and exponent on the grid: the rate of the saturating term
        (normalised by the RMS flux) and the flux's own rate (the refitted inductance)."""
        out = []
        for name, lam in s.labelled("momentum").items():
            ratio = lam / rms(lam)
            rate = np.gradient(lam, s.t)
            out += [FeatureGroup(name, f"n = {n}", list(self.feature_names),
                                 np.stack([np.gradient(lam * np.abs(ratio) ** (n - 1), s.t), rate], axis=1),
                                 grid=(float(n), rms(lam))) for n in FEATURE_EXPONENTS]
        return out

    def feature_start(self, cand, evidence):
        """The knee flux, the exponent and the inductance from the regression (its convention is
        an effort taken from the junction, :math:`-d`): with :math:`c` the saturating term's
        coefficient, :math:`\\lambda_s = \\lambda_r (-c L'/L)^{-1/(n-1)}`; the :math:`\\dot\\lambda`
        coefficient :math:`c_1` gives :math:`L' = L / (1 - c_1)`; clipped to the bounds.  None for
        a law-form inductor or a coefficient of the wrong sign (no saturation)."""
        term, linear = (evidence.coefficients.get(n) for n in self.feature_names)
        knee, exponent, own = cand.params
        if (term is None or not np.isfinite(term) or term >= 0 or len(evidence.grid) != 2
                or not own.description.startswith("inductance")):
            return None
        n, lam_r = evidence.grid
        value = own.guess
        if linear is not None and np.isfinite(linear) and linear < 1.0:
            value = own.clipped(own.guess / (1.0 - float(linear)))
        lam_s = lam_r * (-float(term) * value / own.guess) ** (-1.0 / (n - 1.0))
        return {knee.name: knee.clipped(lam_s), exponent.name: exponent.clipped(n), own.name: value}

    def propose(self, site):
        out = []
        for element in inductors(site):
            name = element.name
            lam, i_scale = site.values.get(f"state:{element.state}"), site.scales.flow
            if lam is None:                     # no data: the flux of the junction's current scale
                linear = element.value is not None and float(element.value.value) > 0
                scale = float(element.value.value) * i_scale if linear else site.scales.displacement
            else:
                scale = rms(lam)
            if not (scale > 0 and np.isfinite(scale)):
                continue                        # no flux moves through it: nothing to saturate
            out.append(Proposal(target=name, params=(
                # the knee from a tenth of the RMS flux (far saturated) to a hundred times (unseen)
                ParamSpec(fresh_name(site.taken, f"lambda_sat_{name}"), 3.0 * scale, 0.1 * scale, 100.0 * scale,
                          "Wb", f"flux linkage at which {name} needs twice its linear current"),
                ParamSpec(fresh_name(site.taken, f"n_sat_{name}"), 3.0, 3.0, 11.0, "1",
                          f"exponent of the saturation of {name} (how sharp its knee is)"),
                _own_inductance(element, site.taken, scale, i_scale))))
        return out

    def build(self, graph, cand, values):
        """The I's law times ``1 + Abs(lambda/lambda_s)**(n - 1)``; a linear I keeps its value
        (refitted under its own name), a law gets ``dG*lambda`` (a change of its inverse
        inductance) before it is multiplied."""
        element = graph.elements[cand.target]
        knee, exponent, linear = (sp.Symbol(spec.name) for spec in cand.params)
        refit_own = element.value is not None and linear.name == element.value.name

        def law(old, lam):
            return (old + (0 if refit_own else linear * lam)) * (1 + sp.Abs(lam / knee) ** (exponent - 1))
        return graph.with_law(cand.target, law, description=f"{element.description} (saturating)".strip())

    def explain(self, cand, values, show):
        j = cand.place.name
        knee, exponent, linear = cand.params
        was = f"{linear.guess:.3g} {linear.unit}".strip()
        return (f"the inductor {cand.target} at {j} saturates: its current doubles over the linear law at a "
                f"flux linkage of {show(knee.name)} and grows with its {values[exponent.name]:.2g}th power beyond "
                f"({linear.description.replace(' (refitted)', '')} refitted with it: {show(linear.name)}, "
                f"nominal {was}): saturation of {cand.target}")


def _own_inductance(element, taken, flux_scale: float, i_scale: float) -> ParamSpec:
    """The inductor's own value (from a tenth to ten times it: an inductance fitted to data
    through a saturating core may sit well below the unsaturated one), refitted with the
    saturation; for a law-form inductor a change of its inverse inductance ``dG_<I> lambda``,
    within three times the junction's current over the flux scale either way."""
    name = element.name
    if element.value is not None and float(element.value.value) > 0:
        v = float(element.value.value)
        return ParamSpec(name, v, v / 10, 10 * v, element.value.unit, f"inductance of {name} (refitted)")
    g = i_scale / flux_scale
    return ParamSpec(fresh_name(taken, f"dG_{name}"), 0.0, -3 * g, 3 * g, "1/H",
                     f"change of the inverse inductance of {name} (refitted)")
