"""Simulation of a truth plant with (or without) a concealed effect.

Inputs are zero-order-hold sample tables (the recorded commands).  ``rk4``
integrates each sample interval with ``plant.substeps`` classic RK4 steps;
``lsoda`` (stiff plants) runs scipy's LSODA across the record with the input
held per interval and at most one sample per step.  A plant with held
variables (``plant.hold``, a discrete law such as Kikuuwe friction) is
integrated with ``rk4`` only: the held values are computed at the start of
each sub-step and passed to the right-hand side in the input dict.  The effect may add
states (a Dahl state, a valve lag, a sensor's lag following the outputs), change the inputs
before the plant (a delay, a saturation) and the outputs after it (a sensor).
"""
from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

from .plant import TruthPlant, TruthPlantError

__all__ = ["simulate_truth", "NoEffect", "effect_extra"]


#: Right-hand side evaluations one sample of an ``lsoda`` truth may take (a smooth run takes about
#: 120): a friction so large and sharp that the solver crawls (seed 7's exoskeleton Stribeck
#: friction at its first calibration magnitude: 14 million evaluations in one 5 ms sample) counts
#: as a run that left the finite numbers, so the calibration tries a magnitude ten times smaller.
MAX_EVALS_PER_SAMPLE = 20_000


#: h |lambda_max| an RK4 sub-step of a truth may take (its stability limit is 2.8; 1 keeps it accurate)
RK4_REACH = 1.0
#: most RK4 steps per sample of a truth with held variables, which cannot go to LSODA (nested in
#: its declared sub-steps, over each of which the held values stay those of its start)
MAX_SUBSTEPS = 64


class _TooStiff(Exception):
    pass


def _rk4_substeps(f, s0, dt: float) -> int:
    """RK4 sub-steps per sample interval `dt` that keep h |lambda| within :data:`RK4_REACH` at the
    start state `s0`, lambda the eigenvalues of a central-difference Jacobian of the right-hand
    side `f(s)`.  At rest a smoothed sign law is at its steepest."""
    n = s0.size
    J = np.empty((n, n))
    for j in range(n):
        step = 1e-6 * max(1.0, abs(s0[j]))
        e = np.zeros(n)
        e[j] = step
        J[:, j] = (f(s0 + e) - f(s0 - e)) / (2.0 * step)
    if not np.all(np.isfinite(J)):
        return 1
    lam = float(np.max(np.abs(np.linalg.eigvals(J)))) if n else 0.0
    return int(np.ceil(dt * lam / RK4_REACH - 1e-9)) if lam > 0 else 1


class NoEffect:
    """The identity effect: the truth plant as it is (the nominal model)."""

    kind = "none"
    place = None
    n_states = 0

    def z0(self, plant: TruthPlant) -> np.ndarray:
        return np.zeros(0)

    def delayed_inputs(self, t: np.ndarray, u: dict) -> dict:
        """Inputs as they reach the plant's actuators (delay, clipping), sample tables."""
        return u

    def inputs_now(self, u: dict, z: np.ndarray) -> dict:
        """Inputs seen by the plant given the effect's own states (a lagged valve)."""
        return u

    def extra(self, sig: dict, u: dict, z: np.ndarray) -> tuple[dict, np.ndarray]:
        """Efforts/flows added at junctions and the effect's state derivatives, given the
        plant's local signals `sig` and the commands `u` as recorded (before any lag)."""
        return {}, np.zeros(0)

    #: whether :meth:`read_by_sensors` changes anything (then the simulation computes `extra`)
    changes_sensed_storage = False

    def read_by_sensors(self, y: dict, ext: dict) -> dict:
        """The outputs with a changed storage law in those that read the storage (none here)."""
        return y

    #: whether the effect's states follow the plant's outputs (a sensor's own dynamics: then the
    #: simulation evaluates the outputs within the right-hand side, :meth:`sensor_rates`)
    reads_outputs = False

    def sensor_rates(self, y: dict, z: np.ndarray) -> np.ndarray:
        """The rates the outputs `y` give the effect's states, one per state (0 for a state that
        does not follow them), added to those of :meth:`extra`; none here."""
        return np.zeros(0)

    def sensed(self, y: dict, z: np.ndarray | None = None) -> dict:
        """Outputs as the sensors report them (`z`: the effect's states)."""
        return y


def _at_algebraic_junction(plant: TruthPlant, effect) -> bool:
    """Whether `effect` adds an effort at an ``algebraic`` junction of `plant`."""
    return getattr(effect, "door", None) == "junction" and plant.junction(effect.junction).algebraic


def effect_extra(plant: TruthPlant, effect, x: np.ndarray, ue: dict, uk: dict, z: np.ndarray):
    """``effect.extra`` at plant state `x` (inputs `ue` as the plant sees them, `uk` as recorded,
    effect states `z`), with the flow of an ``algebraic`` junction it acts at solved together with
    the effort it adds there.

    A friction in series with an orifice sets the flow ``v = Q(dP + e(v))``: the orifice's flow
    under the pressure the friction leaves.  With ``e`` falling and ``Q`` rising in their
    arguments the gap ``Q(dP + e(v)) - v`` falls in ``v``, so one root lies between 0 and the
    flow without the effort (widened until it brackets one).  Read at that flow without the
    effort, a viscous friction of the tanks' Q12 was no series resistance but a change of the
    orifice's law that a Coulomb term fitted better (seed 3535, case 054).
    """
    sig = plant.signals(x, ue)
    if not _at_algebraic_junction(plant, effect):
        return effect.extra(sig, uk, z)
    name = effect.junction

    def gap(v):
        return plant.signals(x, ue, effect.extra({**sig, name: v}, uk, z)[0])[name] - v

    v0 = float(sig[name])
    lo, hi = min(0.0, v0), max(0.0, v0)
    width = max(hi - lo, 1e-12 * max(1.0, abs(v0)), np.finfo(float).tiny)
    for _ in range(60):
        g_lo, g_hi = gap(lo), gap(hi)
        if g_lo >= 0.0 >= g_hi:
            break
        if g_lo < 0.0:
            lo -= width
        if g_hi > 0.0:
            hi += width
        width *= 2.0
    else:
        raise TruthPlantError(f"plant {plant.name}: no flow at junction {name} balances the effort "
                              f"{effect.kind} adds there")
    v = v0 if g_lo == g_hi else brentq(gap, lo, hi, xtol=1e-13 * max(abs(lo), abs(hi)), rtol=1e-12)
    return effect.extra({**sig, name: v}, uk, z)


def simulate_truth(plant: TruthPlant, t: np.ndarray, u: dict, effect=None, *, x0=None,
                   signals: bool = False) -> dict:
    """Noise-free outputs of `plant` (with `effect`) at the sample times `t`.

    Parameters
    ----------
    plant : TruthPlant
    t : ndarray, shape (n,), s
        Uniform sample times.
    u : dict input name -> ndarray (n,)
        Commands in the plant's SI units, held from each sample to the next.
    effect : object, optional
        A :mod:`diagnosis.benchmark.effects` effect (default: none).
    x0 : ndarray, optional
        Plant state at ``t[0]`` (default ``plant.x0``); the effect's own states start at theirs.
    signals : bool
        Also return the plant's local signals along the run (``"_signals"``: name -> ndarray)
        and its states (``"_states"``, shape (n, len(plant.x0))).

    Returns
    -------
    dict output name -> ndarray (n,), SI; ``"_finite"`` is False when the
    simulation left the finite numbers (the rest is NaN from there on).
    """
    effect = NoEffect() if effect is None else effect
    t = np.asarray(t, float)
    u = {k: np.asarray(v, float) for k, v in effect.delayed_inputs(t, u).items()}
    names = list(u)
    nx = len(plant.x0)
    s0 = np.concatenate([np.asarray(plant.x0 if x0 is None else x0, float), effect.z0(plant)])

    def f(s, uk, held=None):
        x, z = s[:nx], s[nx:]
        ue = effect.inputs_now(uk, z)
        ext, dz = effect_extra(plant, effect, x, ue, uk, z)
        if held:
            ue = {**ue, **held}
        if effect.reads_outputs:
            y = plant.measure(x, ue, ext) if plant.feedthrough else plant.measure(x, ue)
            dz = dz + effect.sensor_rates(y, z)
        return np.concatenate([plant.rhs(x, ue, ext), dz])

    def held_at(s, uk, h):
        """The plant's held variables at the start of a sub-step (None without any)."""
        if plant.hold is None:
            return None
        x, z = s[:nx], s[nx:]
        ue = effect.inputs_now(uk, z)
        ext, _ = effect_extra(plant, effect, x, ue, uk, z)
        return plant.hold(x, ue, ext, h)

    n = t.size
    states = np.full((n, s0.size), np.nan)
    states[0] = s0
    finite = True
    method, substeps, inner = plant.method, plant.substeps, 1
    if method == "rk4" and n > 1:
        u0, dt = {name: u[name][0] for name in names}, float(t[1] - t[0])
        held0 = held_at(s0, u0, dt / substeps)
        needed = _rk4_substeps(lambda s: f(s, u0, held0), s0, dt)
        if needed > substeps:
            # the effect made the plant stiffer than its sub-steps resolve (a sharp friction on
            # a light junction): its RK4 run would chatter where the law is steep, an artefact
            # that no model of the physics reproduces (seed 1212, case 036)
            # a discrete law's interval is the plant's (the pam's Kikuuwe friction, Z = h / J, is held
            # per 0.25 ms): finer RK4 steps nest inside it, the held values computed once per interval
            if plant.hold is None:
                method = "lsoda"
            else:
                inner = min(-(-needed // substeps), max(MAX_SUBSTEPS // substeps, 1))
    if method == "rk4":
        s = s0.copy()
        for k in range(n - 1):
            uk = {name: u[name][k] for name in names}
            h = (t[k + 1] - t[k]) / substeps
            g = h / inner
            for _ in range(substeps):
                held = held_at(s, uk, h)
                for _ in range(inner):
                    k1 = f(s, uk, held)
                    k2 = f(s + 0.5 * g * k1, uk, held)
                    k3 = f(s + 0.5 * g * k2, uk, held)
                    k4 = f(s + g * k3, uk, held)
                    s = s + g / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
            if not np.all(np.isfinite(s)):
                finite = False
                break
            states[k + 1] = s
    elif method == "lsoda":
        if plant.hold is not None:
            raise TruthPlantError(f"plant {plant.name}: held variables need method 'rk4'")
        from scipy.integrate import solve_ivp
        s = s0.copy()
        for k in range(n - 1):
            uk = {name: u[name][k] for name in names}
            budget = [MAX_EVALS_PER_SAMPLE]

            def rate(_t, y):
                budget[0] -= 1
                if budget[0] < 0:
                    raise _TooStiff
                return f(y, uk)

            try:
                sol = solve_ivp(rate, (t[k], t[k + 1]), s, method="LSODA", rtol=1e-9, atol=1e-12)
            except _TooStiff:       # an effect so sharp the run crawls: treated as a run that fails
                finite = False
                break
            s = sol.y[:, -1]
            if not sol.success or not np.all(np.isfinite(s)):
                finite = False
                break
            states[k + 1] = s
    else:
        raise TruthPlantError(f"plant {plant.name}: unknown method {plant.method!r} (rk4 or lsoda)")

    out = {o.name: np.full(n, np.nan) for o in plant.outputs}
    local = {}
    reads_storage = effect.changes_sensed_storage
    for k in range(n):
        if not np.all(np.isfinite(states[k])):
            break
        x, z = states[k, :nx], states[k, nx:]
        uk = {name: u[name][k] for name in names}
        ue = effect.inputs_now(uk, z)
        ext = effect_extra(plant, effect, x, ue, uk, z)[0] if plant.feedthrough or reads_storage else {}
        y = plant.measure(x, ue, ext) if plant.feedthrough else plant.measure(x, ue)
        y = effect.sensed(effect.read_by_sensors(y, ext), z)
        for o in plant.outputs:
            out[o.name][k] = y[o.name]
        if signals:
            sig = (plant.signals(x, ue, effect_extra(plant, effect, x, ue, uk, z)[0])
                   if _at_algebraic_junction(plant, effect) else plant.signals(x, ue))
            for key, v in sig.items():
                local.setdefault(key, np.full(n, np.nan))[k] = v
    out["_finite"] = finite
    if signals:
        out["_signals"], out["_states"] = local, states[:, :nx]
    return out
