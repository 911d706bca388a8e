"""Co-simulation cost: 130 s of the ``pam`` plant at 1 ms with a Python PI controller in the loop.

Four ways to run the same closed loop (scenario, controller and initial state
from :mod:`cosim_peers`), timed in one process with the same clock (CPU time of
the loop; building and loading not timed):

(a) our FMU (``fmus.export`` of the bond graph ``pam``) in our master
    (``cosim.CoSimulation``; the controller is a ``PythonBlock``);
(b) the same FMU through fmpy's high-level ``FMU2Slave``
    ``setReal`` / ``doStep`` / ``getReal`` loop;
(c) a pythonfmu3 FMU of the same plant (``cosim_peers``; skipped if pythonfmu3
    is not installed);
(d) scipy ``solve_ivp`` with a Python right-hand side restarted every step
    (run for ``--scipy-horizon`` seconds and scaled).

The master's overhead per step is (a) minus what the loop must do anyway: the
FMU's own ``doStep`` (a loop of raw ``fmi2DoStep`` calls) and the controller
(a loop of ``PIController.step`` calls).  Target (issue 4): at most 5 us per
step per FMU, at least 2x faster than (b) and 100x faster than (d).

Run:  python benchmarks/cosim.py [--horizon 130] [--scipy-horizon 10] [--skip-pythonfmu3]
"""
from __future__ import annotations

import argparse
import ctypes
import importlib.util
import math
import sys
import tempfile
from pathlib import Path

import numpy as np

# This file is named like the package it measures: the repository root must come
# before benchmarks/ on sys.path, and the peers module is loaded by file name.
_HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(_HERE.parent))
_spec = importlib.util.spec_from_file_location("cosim_peers", _HERE / "cosim_peers.py")
peers = importlib.util.module_from_spec(_spec)
sys.modules["cosim_peers"] = peers
_spec.loader.exec_module(peers)

import plants.library as library  # noqa: E402
from cosim import CoSimulation, FMUComponent, Port, PythonBlock  # noqa: E402
from fmus import export  # noqa: E402

CLOCK = peers.CLOCK


class Controller(PythonBlock):
    """The scenario's PI controller and set-point as one block: psi (deg) -> u1, u2 (V)."""

    def __init__(self, scenario):
        self.ctrl = peers.make_controller(scenario)
        self.setpoint = peers.setpoint_function(scenario)
        self._last_t = None
        super().__init__("pi", inputs=[Port("psi", "deg")],
                         outputs=[Port("u1", "V"), Port("u2", "V")])

    def output(self, t):
        # PIController.step also advances the integral, as in the other loops; the
        # master may ask twice for the outputs at t0 (start, then the first step)
        if t != self._last_t:
            self._last_t = t
            self.y[0], self.y[1] = self.ctrl.step(self.u[0], self.setpoint(t))


def _start_values(scenario) -> dict:
    psi, dpsi, P1, P2 = peers.initial_state(scenario)
    J = library.build("pam").equations().param_values["J"]
    v = peers.initial_command(scenario)
    return {"q_psi": psi, "p_J": J * dpsi, "P_1": P1, "P_2": P2,
            "u1": scenario.u0 + v, "u2": scenario.u0 - v}


def run_master(fmu, scenario, T) -> dict:
    """(a) our FMU in our master."""
    plant = FMUComponent(fmu, "plant", start_values=_start_values(scenario))
    sim = CoSimulation([plant, Controller(scenario)],
                       [("plant.psi", "pi.psi"), ("pi.u1", "plant.u1"), ("pi.u2", "plant.u2")],
                       step=scenario.dt)
    c0 = CLOCK()
    res = sim.run(T, progress=False)
    cpu = CLOCK() - c0
    n = res.info["n_steps"]
    return {"name": "our FMU in our master", "us_per_step": 1e6 * cpu / n, "steps": n,
            "psi": res["plant.psi"], "est_full_s": cpu / n * scenario.steps}


def _slave(fmu, scenario):
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave
    md = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    slave = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(fmu)),
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="plant")
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    start = _start_values(scenario)
    slave.setReal([vr[k] for k in start], list(start.values()))
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    return slave, vr


def run_fmpy(fmu, scenario, T) -> dict:
    """(b) the same FMU through fmpy's high-level FMU2Slave calls."""
    slave, vr = _slave(fmu, scenario)
    ctrl, setpoint = peers.make_controller(scenario), peers.setpoint_function(scenario)
    n, dt = round(T / scenario.dt), scenario.dt
    vin, vout = [vr["u1"], vr["u2"]], [vr["psi"]]
    psi = np.empty(n + 1)
    c0 = CLOCK()
    for k in range(n):
        t = k * dt
        psi[k] = slave.getReal(vout)[0]
        slave.setReal(vin, ctrl.step(psi[k], setpoint(t)))
        slave.doStep(t, dt)
    psi[n] = slave.getReal(vout)[0]
    cpu = CLOCK() - c0
    slave.terminate()
    slave.freeInstance()
    return {"name": "same FMU, fmpy FMU2Slave loop", "us_per_step": 1e6 * cpu / n, "steps": n,
            "psi": psi, "est_full_s": cpu / n * scenario.steps}


def floor_costs(fmu, scenario, T) -> dict:
    """What any loop must pay per step: the FMU's doStep alone (raw C call) and the controller."""
    slave, vr = _slave(fmu, scenario)
    do_step, comp = slave.dll.fmi2DoStep, slave.component
    n, dt = round(T / scenario.dt), scenario.dt
    c0 = CLOCK()
    for k in range(n):
        do_step(comp, ctypes.c_double(k * dt), ctypes.c_double(dt), 1)
    fmu_us = 1e6 * (CLOCK() - c0) / n
    slave.terminate()
    slave.freeInstance()
    ctrl, setpoint = peers.make_controller(scenario), peers.setpoint_function(scenario)
    c0 = CLOCK()
    for k in range(n):
        ctrl.step(0.0, setpoint(k * dt))
    return {"doStep": fmu_us, "controller": 1e6 * (CLOCK() - c0) / n}


def main(argv=None) -> dict:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--horizon", type=float, default=peers.SCENARIO.T, help="s (default 130)")
    p.add_argument("--scipy-horizon", type=float, default=10.0, help="s of (d), scaled (default 10)")
    p.add_argument("--skip-pythonfmu3", action="store_true")
    args = p.parse_args(argv)
    sc, T = peers.SCENARIO, args.horizon
    peers.initial_state(sc)
    print(f"pam at {sc.dt * 1e3:g} ms for {T:g} s, PI kp = {sc.kp:g} V/deg, ki = {sc.ki:g} V/(deg s)")
    runs = {}
    with tempfile.TemporaryDirectory() as tmp:
        fmu = export(library.build("pam"), Path(tmp) / "pam.fmu")
        runs["a"] = run_master(fmu, sc, T)
        runs["b"] = run_fmpy(fmu, sc, T)
        floor = floor_costs(fmu, sc, T)
        if not args.skip_pythonfmu3:
            missing = peers.pythonfmu3_missing()
            if missing:
                print(missing)
            else:
                try:
                    runs["c"] = peers.run_pythonfmu3(peers.build_pythonfmu3_plant(tmp), T=T)
                except peers.PeerUnavailable as exc:
                    print(f"skipping (c): {exc}")
    runs["d"] = peers.run_solve_ivp(T=min(T, args.scipy_horizon))
    a = runs["a"]["us_per_step"]
    print(f"\n{'variant':<38} {'us/step':>9} {'x (a)':>8}")
    for key, r in runs.items():
        note = f"  ({r['T'] if 'T' in r else T:g} s run, scaled)" if key == "d" else ""
        print(f"({key}) {r['name']:<34} {r['us_per_step']:9.1f} {r['us_per_step'] / a:8.1f}{note}")
    overhead_a = a - floor["doStep"] - floor["controller"]
    overhead_b = runs["b"]["us_per_step"] - floor["doStep"] - floor["controller"]
    print(f"\nfloor: the FMU's doStep alone {floor['doStep']:.1f} us, the controller alone "
          f"{floor['controller']:.1f} us per step")
    print(f"master overhead per step per FMU (a - floor): {overhead_a:.1f} us   (target <= 5 us)")
    print(f"fmpy high-level overhead (b - floor):         {overhead_b:.1f} us")
    same = float(np.max(np.abs(runs["a"]["psi"] - runs["b"]["psi"])))
    print(f"(a) vs (b) psi: max |difference| {same:.3g} deg (same FMU, same controller)")
    if not math.isfinite(same) or same > 1e-9:
        print("WARNING: (a) and (b) disagree")
    return runs


if __name__ == "__main__":
    main()
