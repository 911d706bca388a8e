"""Where a mismatch lives: in time (significant windows) and in operating regime.

Time
    :func:`significant_windows` averages the residual over a short moving
    window of :math:`w` samples; white noise of std :math:`\\sigma` averages
    to std :math:`\\sigma/\\sqrt w`, so the samples where the average exceeds
    :math:`z\\,\\sigma/\\sqrt w` (``z = 4``) are significant.  Runs closer than
    :math:`w` samples are merged, runs shorter than :math:`w` dropped; the edges
    are resolved to about :math:`w/2` samples.
Regime
    :func:`regime_variables` lists what the operating point is made of: the
    velocity (flow) of every I element, the force/torque/pressure (effort) of
    every C element, the other states (chamber pressures ...) and the
    recorded inputs.  :func:`locate_regime` asks which of them a signal (the
    residual, or better a located extra effort) depends on, through three
    features of increasing freedom: the **sign** of the variable (3 classes:
    negative, near zero, positive), its **magnitude** and its **level**
    (8 quantile classes each).  The share explained is the coefficient of
    determination of the class means,

    .. math:: R^2 = 1 - \\frac{\\sum_k (r_k - \\bar r_{c(k)})^2}{\\sum_k (r_k - \\bar r)^2},

    and the simplest feature within 0.05 of the best one is reported.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import DiagnosisError

__all__ = ["significant_windows", "regime_variables", "RegimeFinding", "locate_regime"]

_Z = 4.0              # significance of the averaged residual, in its noise stds
_N_BINS = 8
_SIMPLER_BY = 0.05    # a simpler feature wins when within this much R^2 of the best
_FLOW_WORD = {"translation": "velocity", "rotation": "angular velocity"}
_EFFORT_WORD = {"translation": "force", "rotation": "torque", "hydraulic": "pressure",
                "pneumatic": "pressure", "electrical": "voltage", "thermal": "temperature"}


def significant_windows(t, residual, sigma, *, width: int | None = None, z: float = _Z):
    """Time windows where a residual exceeds its noise.

    Parameters
    ----------
    t : array_like, shape (n,)
        Times, s.
    residual : array_like, shape (n,)
        Measured minus simulated.
    sigma : float
        Measurement-noise std of the residual (same unit).
    width : int, optional
        Moving-average length, samples; default ``max(5, n // 200)``.
    z : float
        Threshold in noise stds of the average.

    Returns
    -------
    list of (float, float)
        ``(t0, t1)`` of each window, s, in time order.

    Examples
    --------
    >>> t = np.linspace(0.0, 10.0, 1001)
    >>> r = np.where((t > 4) & (t < 6), 0.5, 0.0)
    >>> [(round(a, 2), round(b, 2)) for a, b in significant_windows(t, r, 0.01)]
    [(3.99, 6.01)]
    """
    t, r = np.asarray(t, dtype=float), np.asarray(residual, dtype=float)
    if t.shape != r.shape or t.ndim != 1:
        raise DiagnosisError(f"significant_windows: t {t.shape} and residual {r.shape} must be "
                             "1-D of the same length")
    if not (np.isfinite(sigma) and sigma >= 0):
        raise DiagnosisError(f"significant_windows: sigma must be a finite number >= 0; found {sigma!r}")
    n = r.size
    w = max(1, min(n, int(width or max(5, n // 200))))
    avg = np.convolve(r, np.ones(w) / w, mode="same")
    floor = 1e-9 * max(float(np.max(np.abs(r))), 1e-300)   # numerical noise of a noise-free fit
    flags = np.abs(avg) > max(z * sigma / np.sqrt(w), floor)
    runs = _runs(np.flatnonzero(flags))
    merged: list[list[int]] = []
    for a, b in runs:
        if merged and a - merged[-1][1] <= w:
            merged[-1][1] = b
        else:
            merged.append([a, b])
    return [(float(t[a]), float(t[b])) for a, b in merged if b - a + 1 >= w]


def _runs(idx):
    if idx.size == 0:
        return []
    cuts = np.flatnonzero(np.diff(idx) > 1)
    return list(zip(np.r_[idx[0], idx[cuts + 1]], np.r_[idx[cuts], idx[-1]]))


def _augmented_outputs(graph, eqs):
    """Extra outputs (name -> (expression, unit, description)) for I flows and C efforts."""
    from bondgraph.params import DOMAINS

    extra = {}
    for state, (element, _) in eqs.owners.items():
        el = graph.elements.get(element) if state in eqs.state_names else None
        if el is None or el.kind not in ("I", "C"):
            continue
        domain = getattr(el, "domain", "generic") or "generic"
        units = DOMAINS.get(domain, DOMAINS["generic"])
        if el.kind == "I":
            word = _FLOW_WORD.get(domain, "flow")
            extra[f"v_{element}"] = (f"f_{element}", units.flow, f"{word} of {element}")
        else:
            word = _EFFORT_WORD.get(domain, "effort")
            extra[f"e_{element}"] = (f"e_{element}", units.effort, f"{word} in {element}")
    return extra


def regime_variables(model, experiment, x_sim) -> dict:
    """Variables that describe the operating point along a simulation.

    Parameters
    ----------
    model : BondGraph or StateEquations
        With a StateEquations only states and inputs are listed.
    experiment : Experiment
        Its recorded inputs are listed too.
    x_sim : SimRun or ndarray, shape (n, n_states)
        The simulated states at ``experiment.t``.

    Returns
    -------
    dict str -> (ndarray shape (n,), str)
        Values (SI) and a description with the unit, e.g.
        ``{"v_m": (array, "velocity of m (m/s)"), ...}``.
    """
    from bondgraph.system import StateEquations

    from .residuals import input_matrix

    X = np.asarray(getattr(x_sim, "states", x_sim), dtype=float)
    eqs = model if isinstance(model, StateEquations) else model.equations()
    if X.shape != (experiment.t.size, len(eqs.state_names)):
        raise DiagnosisError(f"regime_variables: states of shape {X.shape}; expected "
                             f"({experiment.t.size}, {len(eqs.state_names)}) for states "
                             f"{', '.join(eqs.state_names)}")
    out = {}
    owned = set()
    if not isinstance(model, StateEquations):
        extra = _augmented_outputs(model, eqs)
        if extra:
            from bondgraph.numerics.evaluate import compile_model

            aug = model.copy()
            for name, (expr, unit, _) in extra.items():
                aug.add_output(f"regime__{name}", expr, unit=unit)
            aug_eqs = aug.equations()
            if aug_eqs.state_names == eqs.state_names:
                m = compile_model(aug_eqs, backend="numpy")
                U = input_matrix(aug_eqs, experiment.t, experiment.inputs)
                D = np.tile(m.default_held, (X.shape[0], 1))
                Y = m.h(X, U, t=experiment.t, d=D)
                for name, (expr, unit, desc) in extra.items():
                    out[name] = (Y[:, m.output_index[f"regime__{name}"]], f"{desc} ({unit})")
                owned = {s for s, (el, _) in eqs.owners.items()
                         if s in eqs.state_names and (f"v_{el}" in extra or f"e_{el}" in extra)}
    for j, s in enumerate(eqs.state_names):
        if s not in owned:
            desc = eqs.descriptions.get(s) or f"state {s}"
            out[s] = (X[:, j].copy(), f"{desc} ({eqs.units.get(s, '') or '1'})")
    for name, values in experiment.inputs.items():
        desc = eqs.descriptions.get(name) or f"input {name}"
        out[name] = (np.asarray(values, dtype=float), f"{desc} ({eqs.units.get(name, '') or '1'})")
    return out


@dataclass(frozen=True)
class RegimeFinding:
    """The operating-regime variable a signal depends on most.

    Attributes
    ----------
    variable : str or None
        Name in the regime variables (None when there were none).
    description : str
        Plain language, e.g. ``"sign of v_m (velocity of m (m/s)): mean +0.5 when
        > 0, -0.5 when < 0"``.
    explained : float
        Share of the signal's variance the class means explain, in [0, 1].
    feature : str
        ``"sign"``, ``"magnitude"`` or ``"level"`` (``""`` when none).
    """

    variable: str | None
    description: str
    explained: float
    feature: str = ""


def _classes(v, feature):
    if feature == "sign":
        eps = 0.02 * float(np.sqrt(np.mean(v ** 2)))
        return np.where(v > eps, 2, np.where(v < -eps, 0, 1))
    x = np.abs(v) if feature == "magnitude" else v
    edges = np.unique(np.quantile(x, np.linspace(0, 1, _N_BINS + 1)[1:-1]))
    return np.searchsorted(edges, x, side="right")


def _share(r, labels):
    total = float(np.sum((r - r.mean()) ** 2))
    if total == 0.0:
        return 0.0, {}
    classes, inverse, counts = np.unique(labels, return_inverse=True, return_counts=True)
    class_means = np.bincount(inverse, weights=r) / counts
    fit = class_means[inverse]
    means = {int(c): float(m) for c, m in zip(classes, class_means)}
    return max(0.0, 1.0 - float(np.sum((r - fit) ** 2)) / total), means


def _describe(name, desc, feature, v, r, means, unit):
    u = f" {unit}" if unit else ""
    if feature == "sign":
        pos, neg = means.get(2), means.get(0)
        parts = [f"{m:+.3g}{u} when {name} {w}" for m, w in ((pos, "> 0"), (neg, "< 0"))
                 if m is not None]
        return f"sign of {name}, {desc}: mean " + ", ".join(parts)
    x = np.abs(v) if feature == "magnitude" else v
    trend = "grows" if np.corrcoef(x, r)[0, 1] > 0 else "falls"
    label = f"|{name}|" if feature == "magnitude" else name
    return f"{feature} of {label}, {desc}: the signal {trend} with {label}"


def locate_regime(residual, regime_vars: dict, *, unit: str = "") -> RegimeFinding:
    """Which regime variable (and which feature of it) a signal depends on most.

    Parameters
    ----------
    residual : array_like, shape (n,)
        The signal: an output residual or a located extra effort/flow.
    regime_vars : dict str -> (ndarray shape (n,), str)
        From :func:`regime_variables`.
    unit : str
        Unit of `residual` (for the description).

    Returns
    -------
    RegimeFinding
    """
    r = np.asarray(residual, dtype=float).reshape(-1)
    order = {"sign": 0, "magnitude": 1, "level": 2}
    scored = []
    for name, (values, desc) in regime_vars.items():
        v = np.asarray(values, dtype=float).reshape(-1)
        if v.shape != r.shape:
            raise DiagnosisError(f"locate_regime: regime variable {name!r} has {v.size} values "
                                 f"for {r.size} residual samples")
        if not np.isfinite(v).all() or np.ptp(v) == 0.0:
            continue
        for feature in order:
            share, means = _share(r, _classes(v, feature))
            scored.append((share, feature, name, desc, v, means))
    if not scored:
        return RegimeFinding(None, "no varying regime variable", 0.0)
    top = max(s[0] for s in scored)
    best = min((s for s in scored if s[0] >= top - _SIMPLER_BY),
               key=lambda s: (order[s[1]], -s[0]))
    share, feature, name, desc, v, means = best
    return RegimeFinding(name, _describe(name, desc, feature, v, r, means, unit), share, feature)
