"""The closed-loop scenario of ``benchmarks/cosim.py`` and two of its peers.

``benchmarks/cosim.py`` times 130 s of the ``pam`` plant (antagonistic
pneumatic-muscle joint) at a 1 ms communication step with a Python PI controller
in the loop, run four ways.  This module has what all four share and the two that
do not use our FMU:

* the scenario: :data:`SCENARIO` (step, horizon, gains), :func:`setpoint` (the
  joint-angle reference, deg), :class:`PIController` (two valve commands from the
  angle error), :func:`make_controller`, and :func:`initial_state` (the plant
  at rest on the first set-point, with the controller's integrator preset to
  hold it there);
* (c) :func:`build_pythonfmu3_plant` and :func:`run_pythonfmu3`: the same plant
  as a pythonfmu3 FMU (FMI 3.0 Co-Simulation; the plant class is
  ``benchmarks/pam_pythonfmu3_plant.py``), stepped through fmpy's high-level
  ``FMU3Slave`` (``setFloat64`` / ``doStep`` / ``getFloat64``);
* (d) :func:`run_solve_ivp`: the plant's right-hand side in Python
  (:func:`plants.blockdiagram.pam.derivatives`) integrated by
  ``scipy.integrate.solve_ivp``, restarted at every 1 ms communication step.

Every loop does the same thing per step ``k`` (``t_k = k dt``)::

    u1, u2 = ctrl.step(psi_k, setpoint(t_k))     # psi_k: plant output at t_k, deg
    <plant: hold u1, u2 over [t_k, t_k + dt]>    # -> psi_{k+1}

What is timed is that loop alone (CPU time, ``time.process_time``), including
the controller, the set-point, and storing psi and u.  Building, loading and
initialising the plant are not timed.  ``us_per_step`` is CPU time / steps.

Scipy (d) is the slowest variant.  On a 2-core machine it needs about 0.5 ms of
CPU per 1 ms step, so the full 130 s takes over a minute.  By default it therefore
runs a shorter horizon, the first 10 s segment of the profile (a ramp and a hold),
and its ``us_per_step`` is scaled to the full 130 s (``est_full_s`` in every
result).  The short run underestimates the cost: 488 us/step over the first 10 s
against 523 us/step over the full 130 s, about 7 % low.

pythonfmu3 is a benchmark-only dependency (``pip install pythonfmu3``, not in
``pyproject.toml``).  :func:`pythonfmu3_missing` returns the message to print
when it is not installed, and the (c) functions then raise :class:`PeerUnavailable`.

Run alone (short horizon, both peers, agreement checks)::

    python benchmarks/cosim_peers.py                 # 10 s each
    python benchmarks/cosim_peers.py --horizon 130   # the full scenario (d: over a minute of CPU)
"""
from __future__ import annotations

import argparse
import functools
import math
import shutil
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

_HERE = Path(__file__).resolve().parent
_ROOT = _HERE.parent
if str(_ROOT) not in sys.path:  # run as `python benchmarks/cosim_peers.py`, or imported from benchmarks/
    sys.path.insert(0, str(_ROOT))

from plants.blockdiagram import pam

PLANT_SCRIPT = _HERE / "pam_pythonfmu3_plant.py"
CLOCK = time.process_time          # what every variant's loop is timed with (CPU seconds)

SINE = "sine"


# --------------------------------------------------------------------------
# the scenario
# --------------------------------------------------------------------------
@dataclass(frozen=True)
class Scenario:
    """The closed loop that all four variants of ``benchmarks/cosim.py`` run.

    The reference is made of ``len(levels)`` segments of ``segment`` seconds.  Each
    segment is either a level (deg), reached from the previous level by a
    raised-cosine ramp of ``ramp`` seconds and then held, or :data:`SINE`:
    ``sine_amplitude * sin(2 pi sine_frequency tau)``, with ``tau`` the time into
    the segment.  A whole number of periods fits in a segment, and the segment
    before a sine holds 0.  The reference starts at ``start_level``.

    Why these numbers.  The plant at ``u1 = u2 = u0 = 5 V`` (406 kPa each) rests
    at +10.4 deg.  Muscle 1 is the stronger one.  Holding 0 deg needs
    ``v = -1.77 V``.  The levels stay within -12..+12 deg.  Below about -13 deg
    the muscle-1 valve saturates at 0 V, and venting towards atmospheric pressure
    is too slow to settle within a segment.  Going down is rate-limited: with
    the valves saturated, a 20 deg drop takes about 1.5 s.  That is why the ramps
    last 2 s.

    Gains.  Statically the joint moves about 6 deg per volt of ``v``.  The
    pressures respond with time constants of 1.5 to 5 s (poles at -0.2 to
    -0.7 1/s).  The mechanical mode at 22 Hz is almost undamped (poles at
    -0.05 +- 142j 1/s).  Coulomb friction of up to about 2 N m holds the joint
    whenever the muscles' torque imbalance is smaller than that.  On the whole
    130 s profile (RMS / max tracking error, deg):

    ============  ============  ==========================================
    kp, ki        error         remark
    ============  ============  ==========================================
    1.5, 1.5      1.42 / 7.2
    2, 1          1.25 / 6.9    settles slowly after friction sticks
    **2, 2**      1.14 / 6.7    chosen
    3, 3          0.87 / 6.2    22 Hz ripple on u grows to +-0.46 V
    ============  ============  ==========================================

    A larger kp feeds the joint's 22 Hz ringing back into the valve commands.
    The max error is the rate limit on the 2 s ramps, whatever the gains.
    After an overshoot, friction holds psi about 1 deg off until the integrator
    has built up enough torque.  There is no sustained hunting.
    """

    dt: float = 1e-3                     # s, communication step (= the plant's sample time)
    T: float = 130.0                     # s, horizon
    kp: float = 2.0                      # V/deg
    ki: float = 2.0                      # V/(deg s)
    u0: float = 5.0                      # V, common-mode valve voltage
    u_min: float = 0.0                   # V, valve range
    u_max: float = 10.0                  # V
    start_level: float = 0.0             # deg, reference at t = 0
    segment: float = 10.0                # s
    ramp: float = 2.0                    # s
    levels: tuple = (10.0, -10.0, 12.0, -12.0, 0.0, SINE, SINE, 5.0, -5.0, 8.0, -8.0, 3.0, 0.0)
    sine_amplitude: float = 10.0         # deg
    sine_frequency: float = 0.2          # Hz

    @property
    def steps(self) -> int:
        return round(self.T / self.dt)


SCENARIO = Scenario()


def _setpoint_function(sc: Scenario):
    levels, seg, ramp, start = sc.levels, sc.segment, sc.ramp, sc.start_level
    last = len(levels) - 1
    prev = [start] + [0.0 if v == SINE else v for v in levels[:-1]]
    w = 2.0 * math.pi * sc.sine_frequency
    amp, half_pi_per_ramp = sc.sine_amplitude, math.pi / ramp
    cos, sin = math.cos, math.sin

    def setpoint(t: float) -> float:
        k = int(t // seg)
        if k > last:
            k = last
        elif k < 0:
            return start
        tau = t - k * seg
        target = levels[k]
        if target == SINE:
            return amp * sin(w * tau)
        if tau >= ramp:
            return target
        p = prev[k]
        return p + (target - p) * 0.5 * (1.0 - cos(half_pi_per_ramp * tau))

    return setpoint


_SETPOINT = _setpoint_function(SCENARIO)


def setpoint(t: float) -> float:
    """Joint-angle reference of :data:`SCENARIO` at time ``t`` (s), in deg.

    >>> [round(setpoint(t), 6) for t in (0.0, 1.0, 5.0, 15.0, 61.25, 130.0)]
    [0.0, 5.0, 10.0, -10.0, 10.0, 0.0]
    """
    return _SETPOINT(t)


def setpoint_function(scenario: Scenario = SCENARIO):
    """``setpoint(t)`` for another :class:`Scenario` (the module's :func:`setpoint` is for SCENARIO)."""
    return _SETPOINT if scenario is SCENARIO else _setpoint_function(scenario)


class PIController:
    """Discrete PI controller on the joint-angle error, driving both valves antagonistically.

    Per call, with ``e = ref - psi`` (deg)::

        I_k = I_{k-1} + ki dt e          (integrator, V)
        v   = kp e + I_k                 (V), clipped to [v_min, v_max]
        u1  = u0 + v,  u2 = u0 - v       (V)

    ``[v_min, v_max]`` is the widest range that keeps both ``u1`` and ``u2`` within
    ``[u_min, u_max]``.  Anti-windup is by conditional integration: when ``v`` is
    clipped and ``e`` would push it further out, the integrator keeps its last
    value.  A positive ``v`` raises muscle 1's pressure and lowers muscle 2's,
    which raises psi.

    Parameters
    ----------
    kp : float, V/deg
    ki : float, V/(deg s)
    u0 : float, V
        Common-mode voltage of both valves.
    dt : float, s
        Step between calls.
    v_init : float, V
        Initial integrator value (see :func:`initial_command`).
    u_min, u_max : float, V
        Valve range.

    >>> c = PIController(2.0, 2.0, 5.0, dt=1e-3)
    >>> c.step(0.0, 1.0)
    (7.002, 2.998)
    >>> c.step(0.0, 10.0)          # saturated: u1, u2 clipped, integrator held
    (10.0, 0.0)
    """

    __slots__ = ("_kidt", "dt", "integral", "ki", "kp", "u0", "v_max", "v_min")

    def __init__(self, kp: float, ki: float, u0: float, *, dt: float = SCENARIO.dt, v_init: float = 0.0,
                 u_min: float = SCENARIO.u_min, u_max: float = SCENARIO.u_max):
        self.kp, self.ki, self.u0, self.dt = float(kp), float(ki), float(u0), float(dt)
        self.v_min = max(u_min - u0, u0 - u_max)
        self.v_max = min(u_max - u0, u0 - u_min)
        if self.v_min > self.v_max:
            raise ValueError(f"u0 = {u0} V is outside the valve range [{u_min}, {u_max}] V")
        self.integral = float(v_init)
        self._kidt = self.ki * self.dt

    def step(self, psi_deg: float, ref_deg: float) -> tuple[float, float]:
        """Valve voltages ``(u1, u2)`` for the measured angle and the reference (deg)."""
        e = ref_deg - psi_deg
        integral = self.integral + self._kidt * e
        v = self.kp * e + integral
        if v > self.v_max:
            v = self.v_max
            if e < 0.0:
                self.integral = integral
        elif v < self.v_min:
            v = self.v_min
            if e > 0.0:
                self.integral = integral
        else:
            self.integral = integral
        return self.u0 + v, self.u0 - v


@functools.cache
def _rest(scenario: Scenario) -> tuple[float, tuple[float, ...]]:
    """(v, x) with the plant at rest (no friction torque) at psi = the first set-point."""
    target = math.radians(setpoint_function(scenario)(0.0))
    u0 = scenario.u0
    lo = max(scenario.u_min - u0, u0 - scenario.u_max)
    hi = min(scenario.u_max - u0, u0 - scenario.u_min)

    def rest_angle(v):
        return pam.equilibrium((u0 + v, u0 - v))[0]      # rises with v (muscle 1 pulls psi up)

    a, b = lo + 1e-9, hi - 1e-9
    try:
        ok = rest_angle(a) <= target <= rest_angle(b)
    except ValueError:                                    # no rest angle at a valve limit
        ok = True
    if not ok:
        raise ValueError(f"no valve command holds psi = {math.degrees(target)} deg at rest")
    for _ in range(60):
        mid = 0.5 * (a + b)
        try:
            above = rest_angle(mid) > target
        except ValueError:      # beyond +-0.6 rad: far from the target, on the side of mid's sign
            above = mid > 0.0
        a, b = (a, mid) if above else (mid, b)
    v = 0.5 * (a + b)
    return v, tuple(float(s) for s in pam.equilibrium((u0 + v, u0 - v)))


def initial_command(scenario: Scenario = SCENARIO) -> float:
    """Integrator preset ``v`` (V) that holds the plant at rest on the first set-point (-1.7705 V)."""
    return _rest(scenario)[0]


def initial_state(scenario: Scenario = SCENARIO) -> np.ndarray:
    """Initial plant state ``(psi [rad], dpsi [rad/s], P1 [Pa], P2 [Pa])`` of every variant.

    The rest state (:func:`plants.blockdiagram.pam.equilibrium`) for the
    inputs ``u0 +- initial_command()``, at which psi is the first set-point (0 deg).
    With the integrator preset to that command, the loop starts in equilibrium.
    For the bond-graph FMU of ``pam``, set its states to ``q_psi = psi``,
    ``p_J = J dpsi`` (0 here), ``P_1 = P1`` and ``P_2 = P2``.  Started like that
    and fed (c)'s commands, our FMU gives the same psi as (c) to 1e-13 deg.
    """
    return np.array(_rest(scenario)[1])


def make_controller(scenario: Scenario = SCENARIO) -> PIController:
    """A fresh :class:`PIController` of the scenario, its integrator preset to :func:`initial_command`."""
    return PIController(scenario.kp, scenario.ki, scenario.u0, dt=scenario.dt,
                        v_init=initial_command(scenario), u_min=scenario.u_min, u_max=scenario.u_max)


def _steps(T: float, dt: float) -> int:
    n = round(T / dt)
    if n < 1 or abs(n * dt - T) > 1e-9 * max(1.0, T):
        raise ValueError(f"T = {T!r} s is not a positive whole number of dt = {dt!r} s steps")
    return n


def _result(name, psi, u, cpu, n, dt, T, scenario, **extra) -> dict:
    us = cpu / n * 1e6
    return dict(name=name, us_per_step=us, cpu_s=cpu, steps=n, T=T, dt=dt,
                est_full_s=us * scenario.steps * 1e-6,
                t=np.arange(n + 1) * dt, psi=np.asarray(psi), u=np.asarray(u).reshape(n, 2), **extra)


# --------------------------------------------------------------------------
# (d) scipy solve_ivp, restarted every communication step
# --------------------------------------------------------------------------
SOLVE_IVP_RTOL = 1e-6
SOLVE_IVP_ATOL = (1e-9, 1e-6, 1e-2, 1e-2)     # rad, rad/s, Pa, Pa


def run_solve_ivp(T: float = 10.0, dt: float | None = None, *, method: str = "RK45",
                  rtol: float = SOLVE_IVP_RTOL, atol=SOLVE_IVP_ATOL,
                  scenario: Scenario = SCENARIO) -> dict:
    """(d): the plant's Python right-hand side under ``scipy.integrate.solve_ivp``, restarted every step.

    Per communication step: the controller's command is held, the Kikuuwe
    friction torque is evaluated once at the step's start with ``h = dt``
    (:func:`plants.blockdiagram.pam.kikuuwe_friction`) and held over the whole
    step, and ``solve_ivp(method, (t_k, t_k + dt), x_k)`` integrates
    :func:`plants.blockdiagram.pam.derivatives` (numpy, one state per call) from
    the state the last step ended in.  So, unlike the other variants, friction is
    held per 1 ms step, not per 0.25 ms RK4 sub-step.  For a solver restarted
    every step, holding it per step is the natural choice.  This makes (d) a
    slightly different discretisation of the same plant.  Over the 130 s, psi
    stays within 0.011 deg of ``pam.simulate`` fed the same commands, and the
    closed loop within 0.085 deg of (c).

    Each restart repeats solve_ivp's set-up, including its estimate of an
    initial step.  This per-step overhead is part of what (d) measures: a Python
    model driven by a general-purpose ODE solver from a co-simulation loop.

    Parameters
    ----------
    T : float, s
        Horizon actually simulated (default 10 s, the first segment).  Scale
        ``us_per_step`` for the full scenario; ``est_full_s`` does so.
    dt : float, s
        Communication step (default: the scenario's 1 ms).
    method, rtol, atol
        Passed to ``solve_ivp`` (defaults: RK45, 1e-6, 1e-9 rad / 1e-6 rad/s /
        0.01 Pa).  RK45 takes the whole 1 ms in a single step here, for any rtol
        from 1e-3 (scipy's default) to 1e-9: 8.0 to 8.6 right-hand side calls per
        step, 2 of which estimate the first step.  psi then differs from the
        reference scheme by the same 0.0066 deg over the first 10 s.  That
        difference comes from the friction hold, not from the tolerance.

    Returns
    -------
    dict
        ``us_per_step`` (CPU µs per step of the timed loop), ``est_full_s``
        (``us_per_step`` times the scenario's steps, in s), ``cpu_s``, ``steps``,
        ``T``, ``dt``, ``t`` (s, ``steps + 1``), ``psi`` (deg, ``steps + 1``), ``u``
        (V, ``(steps, 2)``, the commands applied), ``x`` (final state),
        ``nfev`` (right-hand side calls), ``method``.
    """
    from scipy.integrate import solve_ivp

    dt = scenario.dt if dt is None else float(dt)
    n = _steps(T, dt)
    ctrl = make_controller(scenario)
    sp = setpoint_function(scenario)
    derivatives, friction = pam.derivatives, pam.kikuuwe_friction
    atol = np.asarray(atol, dtype=float)

    def rhs(t, x, u, T_f):
        return derivatives(x, u, None, T_f)

    x = initial_state(scenario)
    psi = [0.0] * (n + 1)
    us = [0.0] * (2 * n)
    psi[0] = y = math.degrees(x[0])
    nfev = 0
    u = np.empty(2)
    c0 = CLOCK()
    for k in range(n):
        t = k * dt
        u1, u2 = ctrl.step(y, sp(t))
        us[2 * k] = u[0] = u1
        us[2 * k + 1] = u[1] = u2
        T_f = float(friction(x, None, dt))
        sol = solve_ivp(rhs, (t, t + dt), x, method=method, rtol=rtol, atol=atol, args=(u.copy(), T_f))
        if not sol.success:
            raise RuntimeError(f"solve_ivp failed at t = {t:g} s: {sol.message}")
        nfev += sol.nfev
        x = sol.y[:, -1]
        psi[k + 1] = y = math.degrees(x[0])
    cpu = CLOCK() - c0
    return _result("scipy solve_ivp", psi, us, cpu, n, dt, T, scenario, x=x, nfev=nfev, method=method)


# --------------------------------------------------------------------------
# (c) pythonfmu3 FMU through fmpy's FMU3Slave
# --------------------------------------------------------------------------
class PeerUnavailable(RuntimeError):
    """A peer cannot run here (pythonfmu3 missing, or its FMU does not load); the message says why."""


PYTHONFMU3_HINT = ("pythonfmu3 is not installed: skipping the pythonfmu3 row "
                   "(benchmark-only dependency: pip install pythonfmu3)")


def pythonfmu3_missing() -> str | None:
    """None when pythonfmu3 can be imported, else the message to print and skip its row with."""
    try:
        import pythonfmu3  # noqa: F401
    except ImportError:
        return PYTHONFMU3_HINT
    return None


def build_pythonfmu3_plant(directory) -> Path:
    """Build ``benchmarks/pam_pythonfmu3_plant.py`` into ``<directory>/PamPlant.fmu``; return its path.

    pythonfmu3's ``FmuBuilder`` writes an FMI 3.0 Co-Simulation FMU whose binary is
    pythonfmu3's prebuilt C++ wrapper and whose resources hold the plant script and
    a copy of pythonfmu3.  ``directory`` is created if needed.  Use a temporary
    directory: built FMUs are not committed.

    Raises :class:`PeerUnavailable` when pythonfmu3 is missing.
    """
    missing = pythonfmu3_missing()
    if missing:
        raise PeerUnavailable(missing)
    from pythonfmu3 import FmuBuilder

    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    return Path(FmuBuilder.build_FMU(PLANT_SCRIPT, dest=directory))


def run_pythonfmu3(fmu_path, T: float = 10.0, dt: float | None = None, *,
                   scenario: Scenario = SCENARIO) -> dict:
    """(c): the pythonfmu3 FMU in fmpy's high-level ``FMU3Slave`` loop, the PI controller in the loop.

    Per step: ``setFloat64([u1, u2])``, ``doStep(t_k, dt)``, ``getFloat64([psi])``.
    The initial state is set through the FMU's ``psi0``, ``dpsi0``, ``P1_0`` and
    ``P2_0`` parameters before initialisation.  The FMU is extracted to a temporary
    directory, which is removed afterwards.  The FMU runs its Python in this
    process's interpreter: it adds its resources folder to ``sys.path``, which is
    restored afterwards.

    Returns
    -------
    dict
        As :func:`run_solve_ivp` (without ``nfev`` / ``method``); ``x`` is
        ``(psi [rad], P1, P2)`` read back at the end.

    Raises :class:`PeerUnavailable` when pythonfmu3 is missing or the FMU does not load.
    """
    missing = pythonfmu3_missing()
    if missing:
        raise PeerUnavailable(missing)
    from fmpy import extract, read_model_description
    from fmpy.fmi3 import FMU3Slave

    dt = scenario.dt if dt is None else float(dt)
    n = _steps(T, dt)
    fmu_path = str(fmu_path)
    md = read_model_description(fmu_path)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    unzipdir = extract(fmu_path)
    saved_path = list(sys.path)
    slave = None
    try:
        try:
            loading = FMU3Slave(guid=md.guid, unzipDirectory=unzipdir,
                                modelIdentifier=md.coSimulation.modelIdentifier, instanceName="pam_pythonfmu3")
            loading.instantiate()
        except Exception as exc:  # any load failure, e.g. no shared libpython in this process
            raise PeerUnavailable(f"the pythonfmu3 FMU does not load here: {exc}") from exc
        slave = loading
        x0 = initial_state(scenario)
        slave.setFloat64([vr["psi0"], vr["dpsi0"], vr["P1_0"], vr["P2_0"]], [float(v) for v in x0])
        slave.enterInitializationMode(startTime=0.0)
        slave.exitInitializationMode()

        ctrl = make_controller(scenario)
        sp = setpoint_function(scenario)
        vr_u, vr_psi = [vr["u1"], vr["u2"]], [vr["psi"]]
        set_, do_step, get = slave.setFloat64, slave.doStep, slave.getFloat64
        psi = [0.0] * (n + 1)
        us = [0.0] * (2 * n)
        psi[0] = y = get(vr_psi)[0]
        c0 = CLOCK()
        for k in range(n):
            t = k * dt
            u1, u2 = ctrl.step(y, sp(t))
            us[2 * k] = u1
            us[2 * k + 1] = u2
            set_(vr_u, [u1, u2])
            do_step(t, dt)
            psi[k + 1] = y = get(vr_psi)[0]
        cpu = CLOCK() - c0
        final = slave.getFloat64([vr["psi"], vr["P1"], vr["P2"]])
        slave.terminate()
    finally:
        if slave is not None:
            slave.freeInstance()
        sys.path[:] = saved_path
        shutil.rmtree(unzipdir, ignore_errors=True)
    x = np.array([math.radians(final[0]), final[1], final[2]])
    return _result("pythonfmu3 FMU (fmpy FMU3Slave)", psi, us, cpu, n, dt, T, scenario, x=x)


# --------------------------------------------------------------------------
# agreement checks
# --------------------------------------------------------------------------
def replay_blockdiagram(u, scenario: Scenario = SCENARIO) -> np.ndarray:
    """psi (deg, ``len(u) + 1``) of :func:`plants.blockdiagram.pam.simulate` fed the input sequence ``u``.

    This runs open loop from :func:`initial_state`, with ``u`` a run's recorded
    commands.  It is the reference scheme: 4 RK4 sub-steps per 1 ms, friction held
    per sub-step.
    """
    u = np.asarray(u, dtype=float)
    return pam.simulate(u, len(u) * pam.SAMPLE_TIME, x0=initial_state(scenario))["psi_deg"]


def agreement(a, b) -> dict:
    """Max and RMS of ``|a - b|`` (same length) and the time (s) of the max, at the scenario's step."""
    d = np.abs(np.asarray(a) - np.asarray(b))
    k = int(np.argmax(d))
    return {"max": float(d[k]), "rms": float(np.sqrt(np.mean(d * d))), "t_max": k * SCENARIO.dt}


def tracking(run: dict, scenario: Scenario = SCENARIO) -> dict:
    """Max and RMS of the tracking error psi - setpoint (deg) of a run."""
    sp = setpoint_function(scenario)
    ref = np.array([sp(t) for t in run["t"]])
    return agreement(run["psi"], ref)


# --------------------------------------------------------------------------
# standalone use
# --------------------------------------------------------------------------
def _fmt_agree(a: dict) -> str:
    return f"max {a['max']:.3g} deg (at t = {a['t_max']:.3f} s), rms {a['rms']:.3g} deg"


def main(horizon: float = 10.0, skip_scipy: bool = False, skip_pythonfmu3: bool = False) -> dict:
    """Run (c) and (d) for ``horizon`` seconds of the scenario; print µs/step and agreement."""
    sc = SCENARIO
    print(f"pam closed loop: dt = {sc.dt * 1e3:g} ms, PI kp = {sc.kp:g} V/deg, ki = {sc.ki:g} V/(deg s), "
          f"u0 = {sc.u0:g} V; horizon run here {horizon:g} s of {sc.T:g} s")
    initial_state(sc)          # the rest-state bisection, outside any timing
    runs = {}
    if not skip_pythonfmu3:
        msg = pythonfmu3_missing()
        if msg:
            print(msg)
        else:
            with tempfile.TemporaryDirectory(prefix="pam_pythonfmu3_") as tmp:
                try:
                    fmu = build_pythonfmu3_plant(tmp)
                    runs["c"] = run_pythonfmu3(fmu, T=horizon)
                except PeerUnavailable as exc:
                    print(f"skipping the pythonfmu3 row: {exc}")
    if not skip_scipy:
        runs["d"] = run_solve_ivp(T=horizon)

    print(f"{'variant':<34} {'us/step':>9} {'steps':>7} {'130 s est. (s)':>15}")
    for key, r in runs.items():
        print(f"({key}) {r['name']:<30} {r['us_per_step']:9.1f} {r['steps']:7d} {r['est_full_s']:15.1f}")
    if runs and horizon < sc.T:
        print(f"    ran {horizon:g} s; the last column scales us/step to the full {sc.T:g} s")
    if "d" in runs:
        print(f"    solve_ivp: {runs['d']['method']}, {runs['d']['nfev'] / runs['d']['steps']:.1f} "
              "right-hand side calls per step, friction held per 1 ms step")
    for key, r in runs.items():
        ref = replay_blockdiagram(r["u"])
        print(f"({key}) vs pam.simulate on its own inputs: {_fmt_agree(agreement(r['psi'], ref))}")
        print(f"({key}) tracking error:                    {_fmt_agree(tracking(r))}")
    if "c" in runs and "d" in runs:
        print(f"(c) vs (d), closed loop:                 {_fmt_agree(agreement(runs['c']['psi'], runs['d']['psi']))}")
    return runs


def _parse(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--horizon", type=float, default=10.0,
                   help="seconds of the scenario to run (default: %(default)s)")
    p.add_argument("--skip-scipy", action="store_true", help="do not run (d)")
    p.add_argument("--skip-pythonfmu3", action="store_true", help="do not run (c)")
    return p.parse_args(argv)


if __name__ == "__main__":
    args = _parse()
    main(horizon=args.horizon, skip_scipy=args.skip_scipy, skip_pythonfmu3=args.skip_pythonfmu3)
