"""Scenario ``pam-pi``: the PAM joint exported as an FMU under a PI angle loop in the master.

The plant is the antagonistic pneumatic-muscle joint of seed 000 (``pam``,
Co-Simulation FMU: 1 ms communication step, 4 internal RK4 sub-steps with
Kikuuwe friction held per sub-step).  The controller is a discrete PI on the
joint angle (deg) whose output ``v`` (V) is split antagonistically:
``u1 = u0 + v``, ``u2 = u0 - v`` (muscle 1 pulls towards positive angles), within
the valves' 0-10 V range.  The joint starts at rest at ``u1 = u2 = u0``.

The plant is slow (pressures settle over about a second) and the friction
sticks, so a plain PI settles within a few degrees, with overshoot on the
large steps; the UKF-based controllers of seed 000 are a later scenario.

Run:  python -m reproductions.pam_pi [OUTPUT_DIR]
"""
from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import numpy as np

import plants.library as library
from plants.blockdiagram import pam
from fmus import export

from cosim.blocks import PI, Antagonistic, Table
from cosim.fmu_component import FMUComponent
from cosim.master import CoSimulation

U0 = 5.0          # V, common valve command (both muscles half open)
V_MAX = 5.0       # V, so u1, u2 stay in 0...10 V
KP, KI = 0.8, 1.0   # V/deg, V/(deg s): tuned by hand on this plant


NAME = "pam-pi"
DESCRIPTION = "PAM joint FMU under a plain PI angle loop (setpoint steps of 10-20 deg)"


def simulate(output_dir=None, *, t_end: float = 13.0, step: float = 1e-3):
    """Co-simulate the PI-controlled PAM joint.

    Parameters
    ----------
    output_dir : path-like, optional
        Write ``cosim_pam_pi.csv`` and ``cosim_pam_pi.png`` there.
    t_end, step : float, s
        Duration and communication step.

    Returns
    -------
    CosimResult
        Signals ``reference.y`` (deg), ``plant.psi`` (deg), ``plant.u1``, ``plant.u2`` (V),
        ``plant.tau`` (N m), ``pi.u`` ... as named by the connections.
    """
    with tempfile.TemporaryDirectory() as tmp:
        fmu = export(library.build("pam"), Path(tmp) / "pam.fmu")
        reference = Table("reference", [0.0, 1.0, 4.0, 7.0, 10.0], [0.0, 10.0, -10.0, 15.0, 0.0],
                          unit="deg", interpolation="hold")
        pi = PI("pi", KP, KI, u_min=-V_MAX, u_max=V_MAX, unit_in="deg", unit_out="V",
                output="v")
        psi, _, P1, P2 = pam.equilibrium([U0, U0])   # rest state (rad, rad/s, Pa, Pa)
        plant = FMUComponent(fmu, "plant", start_values={
            "u1": U0, "u2": U0, "P_1": P1, "P_2": P2, "q_psi": psi})
        sim = CoSimulation(
            [reference, pi, Antagonistic("split", U0, unit="V"), plant],
            [("reference.y", "pi.r"), ("plant.psi", "pi.y_m"), ("pi.v", "split.v"),
             ("split.u1", "plant.u1"), ("split.u2", "plant.u2")],
            step=step)
        result = sim.run(t_end)
    if output_dir is not None:
        out = Path(output_dir)
        out.mkdir(parents=True, exist_ok=True)
        result.to_csv(out / "cosim_pam_pi.csv")
        fig = result.plot(["reference.y", "plant.psi", "plant.u1", "plant.u2", "plant.tau"])
        fig.savefig(out / "cosim_pam_pi.png", dpi=120)
    return result


def settled_error(result) -> float:
    """Largest |reference - angle| (deg) over the last 0.5 s of each 3 s setpoint segment."""
    late = (result.t - 1.0) % 3.0 > 2.5
    return float(np.abs(result["reference.y"] - result["plant.psi"])[late].max())


def run(plot_dir=None, *, quick: bool = False) -> dict:
    """The scenario's numbers (JSON-ready); CSV and plot in `plot_dir` if given.

    ``quick`` runs the first 4 s only (one setpoint step), for tests.
    """
    result = simulate(plot_dir, t_end=4.0 if quick else 13.0)
    n = result.info["n_steps"]
    return {"settled_error_deg": settled_error(result), "steps": n,
            "us_per_step": 1e6 * result.info["wall_time"] / n}


if __name__ == "__main__":
    res = simulate(sys.argv[1] if len(sys.argv) > 1 else "cosim-output")
    print(f"{res.info['n_steps']} steps in {res.info['wall_time']:.2f} s "
          f"({1e6 * res.info['wall_time'] / res.info['n_steps']:.1f} us/step); "
          f"settled |error| < {settled_error(res):.3f} deg")
