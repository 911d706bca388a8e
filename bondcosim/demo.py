"""``bondcosim demo``: the main job on built-in defaults.

Derive and print the equations of every built-in textbook graph, draw each
to PNG, simulate the mass-spring-damper step response and the DC motor
start-up and plot them, then compare the exoskeleton's and the PAM joint's
bond graphs with the papers' block-diagram / state-space models, export the
PAM joint as an FMU and close a PI angle loop around it in the co-simulation
master, run the papers' closed-loop scenarios (``reproductions``), a small
Monte-Carlo of the UKF scenario on a local Dask cluster (``sweeps``), and end
with one diagnosis of a recording with a concealed effect (``diagnosis``).
"""
from __future__ import annotations

import time
from pathlib import Path

__all__ = ["run_demo"]

_TEXTBOOK = ["mass-spring-damper", "dc-motor", "rlc", "coupled-tanks", "geared-inertias",
             "resistor-loop", "resistor-loop-nl"]


def _step(message: str) -> None:
    print(f"== {message}", flush=True)


def run_demo(output_dir="demo-output", *, quick: bool = False) -> dict:
    """Run the demo, writing figures and CSVs into `output_dir`; returns the paths written.

    ``quick`` shortens the closed-loop scenarios (for tests).
    """
    import matplotlib
    matplotlib.use("Agg")
    from plants import library
    from bondgraph.numerics.simulation import simulate

    out = Path(output_dir)
    out.mkdir(parents=True, exist_ok=True)
    written = {}
    start = time.perf_counter()
    for k, name in enumerate(_TEXTBOOK, 1):
        _step(f"[{k}/{len(_TEXTBOOK)}] {name}: {library.describe(name)}")
        graph = library.build(name)
        print(graph.equations().pretty())
        path = out / f"{graph.name}.png"
        graph.draw(path)
        written[f"{name}.png"] = path
        print(f"   drawing: {path}\n")

    _step("simulating the mass-spring-damper step response (F = 1 N, 20 s)")
    msd = simulate(library.build("mass-spring-damper"), (0.0, 20.0), output_interval=0.01)
    written["msd.csv"] = out / "mass_spring_damper.csv"
    msd.to_csv(written["msd.csv"])
    fig = msd.plot(["x", "v"])
    fig.suptitle("mass-spring-damper: response to a 1 N step")
    written["msd.png"] = out / "mass_spring_damper_response.png"
    fig.savefig(written["msd.png"], dpi=150)
    print(f"   final position {msd['x'][-1]:.4f} m (static deflection F/k = {1.0 / 4.0:.4f} m)")

    _step("simulating the DC motor start-up (V = 12 V, 0.5 s)")
    motor = simulate(library.build("dc-motor"), (0.0, 0.5), output_interval=1e-3)
    written["motor.csv"] = out / "dc_motor.csv"
    motor.to_csv(written["motor.csv"])
    fig = motor.plot(["i", "w_m", "w_L"])
    fig.suptitle("DC motor with gearbox: start-up at 12 V")
    written["motor.png"] = out / "dc_motor_response.png"
    fig.savefig(written["motor.png"], dpi=150)
    print(f"   load speed after 0.5 s: {motor['w_L'][-1]:.2f} rad/s")

    _step("exoskeleton (seed 004): bond graph vs the paper's block diagram, Sec. 5.1 test")
    from .compare import compare
    result = compare("exoskeleton", plot_dir=out)
    written["exo.png"] = out / "exoskeleton_section_5_1.png"
    library.build("exoskeleton").draw(out / "exoskeleton.png")
    written["exo_graph.png"] = out / "exoskeleton.png"
    print(f"   A, B, C, D equal eq. (3): {result['matrices_equal']}; max |error| "
          + ", ".join(f"{k} {v:.2g}" for k, v in result["max_abs_error"].items()))

    _step("antagonistic PAM joint (seed 000): bond graph vs state-space model (11a), 20 s Fig. 8-like inputs")
    result = compare("pam", plot_dir=out)
    written["pam.png"] = out / "pam_fig8.png"
    library.build("pam").draw(out / "pam.png")
    written["pam_graph.png"] = out / "pam.png"
    print("   max |error| " + ", ".join(f"{k} {v:.2g}" for k, v in result["max_abs_error"].items()))

    _step("PAM joint as an FMU: validate it, then close a PI angle loop in the co-simulation master")
    from fmpy.validation import validate_fmu

    from reproductions import pam_pi
    from fmus import export
    from fmus.info import fmu_info
    written["pam.fmu"] = export(library.build("pam"), out / "pam.fmu")
    info = fmu_info(written["pam.fmu"])
    problems = validate_fmu(str(written["pam.fmu"]))
    print(f"   {written['pam.fmu']}: FMI {info['fmi_version']} {', '.join(info['interfaces'])}, "
          f"{len(info['variables'])} variables; fmpy validation: "
          + ("no problems" if not problems else "; ".join(problems)))
    loop = pam_pi.simulate(out)
    written["cosim.png"] = out / "cosim_pam_pi.png"
    err = pam_pi.settled_error(loop)
    print(f"   {loop.info['n_steps']} steps of 1 ms in {loop.info['wall_time']:.2f} s "
          f"({1e6 * loop.info['wall_time'] / loop.info['n_steps']:.1f} us/step); "
          f"settled |angle error| <= {err:.1f} deg")

    _step("the papers' closed loops: plant FMUs with estimators and controllers in the master")
    from .demo_scenarios import run_scenarios
    written.update(run_scenarios(out, quick=quick, step=_step))

    _step("Monte-Carlo: the paper's UKF on rigs whose orifice areas and friction vary by +-20 % (local Dask cluster)")
    from .demo_montecarlo import run_montecarlo
    written.update(run_montecarlo(out, quick=quick))

    _step("diagnosis: a recording the nominal PAM model does not explain - where, what, and the fix")
    from .demo_diagnosis import run_diagnosis
    written.update(run_diagnosis(out, quick=quick))

    _step(f"done in {time.perf_counter() - start:.1f} s; files in {out.resolve()}")
    for key, path in written.items():
        print(f"   {path}")
    return written
