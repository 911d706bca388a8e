"""A nominal a few per cent off (``python -m diagnosis.benchmark --detune F``).

A model written from a rig's documentation never has the rig's exact values.  With ``--detune F``
each case's nominal model (not its truth) has one linear storage element's value (an I's inertance
or a C's stiffness or compliance: a mass, an inertia, a spring, a capacity) scaled by a factor
``1 +- U(F/2, F)``, drawn from the case's own seed, so the cases are the same draws as without it.
Plants whose storages are all laws (the pneumatic cylinders) keep their nominal.  With
``--detune-elements ICR`` the element may be a linear R too (a damper, a winding's resistance, a
pipe's); the draw of the element then differs from the storages-only one.

The concealed effect is then scored on the answers but the ``nominal_value`` ones (a null with a
detuned nominal answered ``nominal_value`` alone is no false alarm), and whether an answer named
the detuned value is reported beside it (:func:`diagnosis.benchmark.run.score_case`).
"""
from __future__ import annotations

import numpy as np

from ..errors import BenchmarkError

__all__ = ["detuned_nominal"]


def detuned_nominal(model: str, seed: int, fraction: float, kinds: str = "IC"):
    """``(graph, detuned)``: the library model `model` with one linear element's value scaled (an
    element of `kinds`: ``"IC"``, the storages, or ``"ICR"``, resistances too), and what was
    detuned (``element``, ``parameter``, ``nominal`` (the truth's value, SI), ``factor``); ``{}``
    and the model itself when it has no such element or `fraction` is 0."""
    from plants import load
    graph = load(model)
    if not fraction > 0:
        return graph, {}
    if not fraction < 1:
        raise BenchmarkError(f"--detune must be a fraction in (0, 1), got {fraction}")
    if kinds not in ("IC", "ICR"):
        raise BenchmarkError(f"--detune-elements must be IC or ICR, got {kinds!r}")
    storages = [e for e in graph.elements.values()
                if e.kind in kinds and getattr(e, "value", None) is not None and float(e.value.value) > 0]
    if not storages:
        return graph, {}
    rng = np.random.default_rng([int(seed), 11])
    element = storages[int(rng.integers(len(storages)))]
    factor = 1.0 + float(rng.choice([-1.0, 1.0])) * float(rng.uniform(fraction / 2, fraction))
    value = float(element.value.value)
    return (graph.with_params({element.value.name: value * factor}),
            {"element": element.name, "parameter": element.value.name, "nominal": value, "factor": factor})
