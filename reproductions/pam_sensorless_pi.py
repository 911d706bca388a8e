"""Scenario ``pam-sensorless-pi``: UKF-based encoder-less angle PI and torque-sensor-less torque PI.

Seed 000 ([1]_), Section IV.C and Figs. 13-14: the angle (a) or the torque
(b) of the antagonistic PAM joint is estimated by a UKF from the two muscle
pressures only, and the discrete PI of Section IV.C
(:class:`~estimators.DiscretePI`, :math:`T_P`, :math:`T_I` of the paper,
:math:`\\beta = 5.5` V, 1 ms) closes the loop on the estimate.  The true
angle / torque is used only to evaluate the tracking, by the paper's
steady-state tracking performance
(:mod:`reproductions._pam_sensorless_metrics`): 94.75 % (angle) and
95.0 % (torque) reported.

Set-up (:mod:`reproductions._pam_sensorless_loop`):

* plant: the "rig" FMU (:mod:`reproductions._pam_rig`: ``pam`` with
  perturbed orifice areas, polytropic indexes and friction), started at its
  rest state under :math:`\\beta`; the torque loop uses the rig locked at
  :math:`\\psi = 0` (``pam-locked``), as the paper's torque experiments
  ("the joint angle was fixed at 0 deg", Section IV-A 2) and its torque meter
  require;
* sensors: the two pressures with white noise of 10 kPa (E8F2, +-1 % of
  1 MPa; the paper's :math:`R = 10^8` Pa^2);
* UKF: nominal Table II model, the paper's :math:`P(0), Q, R`, Julier sigma
  points with :math:`\\kappa = 0`, started at the nominal rest state;
* references: step-like, within +-20 deg and +-2 N m, 10 s per step.

Readings (see ``docs/reproduction_pam_sensorless_pi.md``): the angle error
``e`` fed to the PI is in degrees (the model output :math:`\\psi` of eq.
(11b)); the rad reading is run too (full mode) and reported as
``angle_rad_reading``.  :math:`C = T_I T_{stp}` (the ``"gain"`` reading of
:class:`~estimators.DiscretePI`).  The rig cannot hold angles below about
-14 deg (both valves saturated; friction-free rest -20 deg), so the angle
references stay within -10...+20 deg and the performance is divided by their
span (30 deg), not by 40 deg.

Run:  python -m reproductions.pam_sensorless_pi [OUTPUT_DIR]

References
----------
.. [1] T. Shin, T. Ibayashi, K. Kogiso, "Detailed dynamic model of antagonistic
   PAM system and its experimental validation: sensor-less angle and torque
   control with UKF", seed 000 (``docs/references.md``).
"""
from __future__ import annotations

import json
import sys
import tempfile
from pathlib import Path

import numpy as np

from ._pam_sensorless_loop import build_loop
from ._pam_sensorless_metrics import plot_loop, steady_state_performance

NAME = "pam-sensorless-pi"
DESCRIPTION = "UKF-based encoder-less angle PI and torque-sensor-less torque PI on the PAM rig (seed 000)"

#: The paper's steady-state tracking performance, % (Section IV.C 1-2 of [1]).
PAPER_PCT = {"angle": 94.75, "torque": 95.0}
#: The paper's denominators: the range of its references, +-20 deg and +-2 N m.
PAPER_SPAN = {"angle": 40.0, "torque": 4.0}

#: Reference profiles: (segment length s, step values, steady-state settle time s), full and quick.
PROFILES = {
    ("angle", False): (10.0, (0.0, 10.0, -10.0, 20.0, -5.0, 15.0, 5.0), 7.0),   # deg
    ("angle", True): (5.0, (0.0, 10.0), 3.5),
    ("torque", False): (10.0, (1.0, -1.0, 2.0, -2.0, 0.5, -1.5, 0.0), 7.0),     # N m
    ("torque", True): (4.0, (1.0, -1.0), 3.0),
}
_UNITS = {"angle": "deg", "torque": "N m"}


def simulate(loop: str, *, quick: bool = False, reading: str = "deg", pi_reading: str = "gain",
             seed: int = 0):
    """Co-simulate one loop of Fig. 13 of [1]_ on its reference profile.

    Parameters
    ----------
    loop : {"angle", "torque"}
    quick : bool
        The short profile of :data:`PROFILES` (tests).
    reading : {"deg", "rad"}
        Unit of the angle error fed to the PI (ignored for the torque).
    pi_reading : {"gain", "printed"}
        :math:`C = \\pm T_I T_{stp}` (default) or :math:`\\pm T_I / T_{stp}` as printed.
    seed : int
        Pressure-noise seed.

    Returns
    -------
    CosimResult
        Signals ``reference.y``, ``rig.psi`` (deg), ``rig.tau`` (N m),
        ``rig.P1``, ``rig.P2``, ``sensors.P1``, ``sensors.P2`` (Pa),
        ``ukf.x_psi`` (rad) ..., ``ukf.psi_hat`` (deg), ``ukf.tau_hat`` (N m),
        ``pi.u1``, ``pi.u2`` (V).
    """
    seg, values, _ = PROFILES[(loop, quick)]
    times = seg * np.arange(len(values))
    with tempfile.TemporaryDirectory() as tmp:
        sim = build_loop(loop, times, values, tmp, reading=reading, pi_reading=pi_reading,
                         seed=seed)
        return sim.run(seg * len(values))


def evaluate(loop: str, result, *, quick: bool = False) -> dict:
    """The loop's numbers from a :func:`simulate` result (JSON-ready).

    Returns
    -------
    dict
        :func:`~reproductions._pam_sensorless_metrics.steady_state_performance`
        keys, plus ``paper_pct``, ``unit``, ``estimation_rmse`` (estimate minus
        true, after the first second), ``settle_s``, ``duration_s`` and
        ``performance_pct_paper_span`` (the worst error divided by the
        paper's span, 40 deg or 4 N m, instead of ours).
    """
    _, _, settle = PROFILES[(loop, quick)]
    reference, actual, estimate = _signals(loop, result)
    out = steady_state_performance(result.t, reference, actual, settle=settle)
    late = result.t >= 1.0
    worst = out["worst_steady_state_error"]
    out.update(paper_pct=PAPER_PCT[loop], unit=_UNITS[loop], settle_s=settle,
               performance_pct_paper_span=100.0 * (1.0 - worst / PAPER_SPAN[loop]),
               duration_s=float(result.t[-1]),
               estimation_rmse=float(np.sqrt(np.mean((estimate - actual)[late] ** 2))))
    return out


def _signals(loop, result):
    """Reference, true and estimated signal in deg (angle) or N m (torque)."""
    if loop == "torque":
        return result["reference.y"], result["rig.tau"], result["ukf.tau_hat"]
    ref = result["reference.y"]
    if result.units.get("reference.y") == "rad":
        ref = np.degrees(ref)
    return ref, result["rig.psi"], result["ukf.psi_hat"]


def _save(loop, result, plot_dir, quick):
    out = Path(plot_dir)
    out.mkdir(parents=True, exist_ok=True)
    result.to_csv(out / f"pam_sensorless_{loop}.csv")
    reference, actual, estimate = _signals(loop, result)
    fig = plot_loop(result.t, reference, estimate, actual, result["pi.u1"], result["pi.u2"],
                    quantity=loop, unit=_UNITS[loop], settle=PROFILES[(loop, quick)][2])
    fig.savefig(out / f"pam_sensorless_{loop}.png", dpi=110)
    import matplotlib.pyplot as plt
    plt.close(fig)


def run(plot_dir=None, *, quick: bool = False) -> dict:
    """The scenario's numbers (JSON-ready); CSV and Fig. 14-like plots in `plot_dir` if given.

    Returns
    -------
    dict
        ``{"angle": {...}, "torque": {...}}`` (:func:`evaluate`), each with
        ``steady_state_performance_pct``; in full mode also
        ``angle_rad_reading`` (the angle loop with the error in rad);
        ``reading`` says which readings were used.
    """
    results = {}
    for loop in ("angle", "torque"):
        res = simulate(loop, quick=quick)
        results[loop] = evaluate(loop, res, quick=quick)
        if plot_dir is not None:
            _save(loop, res, plot_dir, quick)
    if not quick:
        results["angle_rad_reading"] = evaluate("angle", simulate("angle", reading="rad"))
    results["reading"] = ("angle error e in deg (model output psi, eq. (11b)); torque error in N m; "
                          "C = T_I*T_stp; torque loop on the locked joint (psi = 0); "
                          "performance = 100 (1 - worst |reference - true| in steady state / "
                          "reference span)")
    return results


if __name__ == "__main__":
    print(json.dumps(run(sys.argv[1] if len(sys.argv) > 1 else "cosim-output"), indent=2))
