"""FMU solvers: accuracy against cost, per 1 ms communication step.

Three models, each run for ``--horizon`` seconds (default 1) with constant inputs:
``exoskeleton`` (7 states, stiff: fastest pole ~1e5 1/s), ``pam-locked`` (the
PAM joint's valves and chambers with the joint held; 2 states, 52 switching
surfaces in the valve laws -- ``pam`` itself has sampled friction, so neither
Dormand-Prince nor Model Exchange applies, and ``pam-frictionless`` swings into a
vanishing chamber within 25 ms) and a 100-state mass-spring-damper chain (``library.mass_spring_chain(50)``).
Each is exported once as an FMI 2.0 FMU (``fmus.export``) and run

* **CS RK4**: our Co-Simulation with the fixed-step RK4 (``solver = 0``) at
  several ``solver_step`` values;
* **CS DoPri**: our Co-Simulation with the embedded Dormand-Prince 5(4)
  (``solver = 1``) at several ``tolerance`` values;
* **ME CVode**: our Model Exchange interface under fmpy's CVode (BDF, dense
  Jacobian by differences; ``fmpy.simulate_fmu(..., fmi_type="ModelExchange",
  solver="CVode", relative_tolerance=...)``), at several tolerances.

*Error*: the largest deviation of any output over the run from a tight reference
(``bondgraph.numerics.simulate`` with scipy's ``DOP853``, rtol 1e-12, atol 1e-14; an
explicit method: the valve laws' kinks give Radau's difference Jacobian NaNs), divided by that output's largest magnitude.  *Cost*:
CPU time (``time.process_time``) per communication step of the whole loop -- for
CS a ``fmi2DoStep`` and a ``fmi2GetReal`` of the outputs per step through ctypes
(about 1 us of the figure is the two calls); for ME fmpy's whole
``simulate_fmu`` divided by the steps (its integrator calls the FMU through
Python callbacks, which dominate).  A CS run whose ``doStep`` returns Discard
(RK4 beyond its stability limit: a non-finite state or a guard left) shows
where it stopped.

Run:  python benchmarks/fmu_solvers.py [--horizon 1] [--models exoskeleton,pam-locked,chain100]
"""
from __future__ import annotations

import argparse
import ctypes
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bondgraph.numerics import simulate  # noqa: E402
import plants.library as library  # noqa: E402
from fmus import default_solver_step, export  # noqa: E402

CLOCK = time.process_time
DT = 1e-3   # communication step, s
#: model -> (graph builder, constant inputs)
MODELS = {
    "exoskeleton": (lambda: library.build("exoskeleton"), {"tau_m": 0.2, "w_h": 0.5}),
    "pam-locked": (lambda: library.build("pam-locked"), {"u1": 7.0, "u2": 3.0}),
    "chain100": (lambda: library.mass_spring_chain(50), {"F": 1.0}),
}
RK4_STEPS = (5e-7, 2e-6, 1e-5, 5e-5, 2e-4, 1e-3)
TOLERANCES = (1e-4, 1e-6, 1e-8, 1e-10)


def reference(graph, inputs, T) -> dict:
    """Outputs on the communication grid from DOP853 at rtol 1e-12 (scipy, compiled f)."""
    eqs = graph.equations()
    res = simulate(graph, (0.0, T), inputs=inputs, method="DOP853", rtol=1e-12, atol=1e-14,
                      output_interval=DT)
    return {o: np.asarray(res[o]) for o in eqs.outputs}


def relative_error(got: dict, ref: dict, units: dict) -> float:
    """max over outputs of max_t |got - ref| / scale, the scale being the largest magnitude
    of any output in the same unit (the chain's far masses barely move in 1 s: their own
    magnitude would turn rounding into a large relative error); inf when a run stopped early."""
    scale = {}
    for name, r in ref.items():
        scale[units[name]] = max(scale.get(units[name], 0.0), float(np.max(np.abs(r))))
    worst = 0.0
    for name, r in ref.items():
        g = got[name]
        if len(g) != len(r):
            return float("inf")
        worst = max(worst, float(np.max(np.abs(g - r))) / max(scale[units[name]], 1e-300))
    return worst


def run_cs(path, inputs, outputs, T, start) -> tuple[dict, float, str]:
    """Our Co-Simulation through raw fmi2DoStep / fmi2GetReal calls: (outputs, us/step, note)."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave
    md = read_model_description(str(path))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    slave = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(path)),
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="bench")
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    values = {**inputs, **start}
    slave.setReal([vr[k] for k in values], list(values.values()))
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    n = round(T / DT)
    out_vr = (ctypes.c_uint * len(outputs))(*[vr[o] for o in outputs])
    buf = (ctypes.c_double * len(outputs))()
    rows = np.empty((n + 1, len(outputs)))
    do_step, get_real, comp = slave.dll.fmi2DoStep, slave.dll.fmi2GetReal, slave.component
    get_real(comp, out_vr, len(outputs), buf)
    rows[0] = buf
    note, done = "", n
    c0 = CLOCK()
    for k in range(n):
        status = do_step(comp, ctypes.c_double(k * DT), ctypes.c_double(DT), 1)
        if status != 0:
            note, done = f"Discard at t = {k * DT:.3g} s", k
            break
        get_real(comp, out_vr, len(outputs), buf)
        rows[k + 1] = buf
    cpu = CLOCK() - c0
    slave.terminate()
    slave.freeInstance()
    got = {o: rows[:done + 1, i] for i, o in enumerate(outputs)}
    return got, 1e6 * cpu / max(done, 1), note


def run_me(path, inputs, outputs, T, rtol) -> tuple[dict, float, str]:
    """Our Model Exchange under fmpy's CVode: (outputs, us/step, note)."""
    from fmpy import simulate_fmu
    c0 = CLOCK()
    try:
        res = simulate_fmu(str(path), fmi_type="ModelExchange", solver="CVode", relative_tolerance=rtol,
                           stop_time=T, output_interval=DT, start_values=inputs, output=list(outputs))
    except Exception as exc:   # noqa: BLE001 -- a benchmark reports any failure of the peer
        return {o: np.array([]) for o in outputs}, float("nan"), f"failed: {exc}"[:60]
    cpu = CLOCK() - c0
    return {o: np.asarray(res[o]) for o in outputs}, 1e6 * cpu / round(T / DT), ""


def bench_model(name, T, tmp) -> list[dict]:
    build, inputs = MODELS[name]
    graph = build()
    eqs = graph.equations()
    outputs = list(eqs.outputs)
    units = {o: eqs.units.get(o, "") for o in outputs}
    path = export(graph, Path(tmp) / f"{name}.fmu")
    c0 = time.perf_counter()
    ref = reference(graph, inputs, T)
    print(f"{name}: {len(eqs.states)} states, default solver_step {default_solver_step(eqs):g} s, "
          f"reference in {time.perf_counter() - c0:.1f} s", flush=True)
    rows = []
    steps = sorted({*RK4_STEPS, default_solver_step(eqs)})
    for h in steps:
        got, us, note = run_cs(path, inputs, outputs, T, {"solver": 0.0, "solver_step": h})
        rows.append({"model": name, "run": "CS RK4", "setting": f"step {h:g} s", "us": us,
                     "error": relative_error(got, ref, units), "note": note})
    for tol in TOLERANCES:
        got, us, note = run_cs(path, inputs, outputs, T, {"solver": 1.0, "tolerance": tol})
        rows.append({"model": name, "run": "CS DoPri", "setting": f"tol {tol:g}", "us": us,
                     "error": relative_error(got, ref, units), "note": note})
    for tol in TOLERANCES:
        got, us, note = run_me(path, inputs, outputs, T, tol)
        rows.append({"model": name, "run": "ME CVode", "setting": f"rtol {tol:g}", "us": us,
                     "error": relative_error(got, ref, units), "note": note})
    return rows


def print_table(rows) -> None:
    print(f"\n{'model':<12} {'run':<9} {'setting':<15} {'us/step':>9} {'rel. error':>11}  note")
    for r in rows:
        err = "-" if not np.isfinite(r["error"]) else f"{r['error']:.1e}"
        us = "-" if not np.isfinite(r["us"]) else f"{r['us']:.1f}"
        print(f"{r['model']:<12} {r['run']:<9} {r['setting']:<15} {us:>9} {err:>11}  {r['note']}")


def main(argv=None) -> list[dict]:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--horizon", type=float, default=1.0, help="simulated time per run, s (default 1)")
    p.add_argument("--models", default=",".join(MODELS), help="comma-separated, of " + ", ".join(MODELS))
    args = p.parse_args(argv)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name in args.models.split(","):
            rows += bench_model(name.strip(), args.horizon, tmp)
    print_table(rows)
    return rows


if __name__ == "__main__":
    main()
