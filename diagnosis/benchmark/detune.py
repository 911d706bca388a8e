"""A nominal a few per cent off (``python -m diagnosis.benchmark --detune F``).

A model written from a rig's documentation never has the rig's exact values.  With ``--detune F``
each case's nominal model (not its truth) has one linear storage element's value (an I's inertance
or a C's stiffness or compliance: a mass, an inertia, a spring, a capacity) scaled by a factor
``1 +- U(F/2, F)``, drawn from the case's own seed, so the cases are the same draws as without it.
Plants whose storages are all laws (the pneumatic cylinders) keep their nominal.  With
``--detune-elements ICR`` the element may be a linear R too (a damper, a winding's resistance, a
pipe's); the draw of the element then differs from the storages-only one.

The recording's initial state is stated to the diagnosis in the detuned model's own terms
(:func:`stated_start`): a user who knows the heater block starts at room temperature states the
heat content their model's capacity gives it, not the rig's (the truth's content with a capacity
13 % off had started the nominal 35 K below the room, seed 4401, case 020).

The concealed effect is then scored on the answers but the ``nominal_value`` ones (a null with a
detuned nominal answered ``nominal_value`` alone is no false alarm), and whether an answer named
the detuned value is reported beside it (:func:`diagnosis.benchmark.run.score_case`).
"""
from __future__ import annotations

import numpy as np

from ..errors import BenchmarkError

__all__ = ["detuned_nominal", "stated_start"]


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


def stated_start(x0: dict | None, graph, detuned: dict) -> dict | None:
    """The initial state `x0` (the truth's, state name -> value) as a user states it to the detuned
    nominal `graph`: the detuned storage's content at the same effort (a C's, ``q = C e`` or
    ``q = e / k``) or flow (an I's, ``p = I f``), its content scaled by the value's factor (or its
    inverse, in stiffness form).  Unchanged without a detuned storage in `x0`.

    >>> from plants import load
    >>> g, d = detuned_nominal("heater-pair", 1, 0.2)
    >>> d["element"], round(d["factor"], 3)
    ('C2', 0.85)
    >>> x0 = stated_start({"q_C1": 592.3, "q_C2": 592.3}, g, d)     # both blocks at 296.15 K
    >>> round(x0["q_C1"], 1), round(x0["q_C2"], 1), round(x0["q_C2"] / g.elements["C2"].value.value, 2)
    (592.3, 503.4, 296.15)
    """
    if not x0 or not detuned:
        return x0
    element = graph.elements[detuned["element"]]
    state = getattr(element, "state", None)
    if element.kind not in ("I", "C") or state not in x0:
        return x0
    factor = detuned["factor"]
    scale = 1.0 / factor if getattr(element, "stiffness_form", False) else factor
    return {**x0, state: float(x0[state]) * scale}
