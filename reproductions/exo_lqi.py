"""Scenario ``exo-lqi``: seed 004 Section 5.2 -- Kalman observer + LQI with
double integral action around the exoskeleton FMU.

Plant: the exoskeleton bond graph (Fig. 6 of [1]_, 7 states with the absolute
trunk angle, ``b_f = 0`` as in the paper's simulations) exported as an FMU.
Controller (Fig. 12), run in the master at ``dt = 0.1 ms``:

- observer from motor velocity and sensor torque (eq. (5)) on the 6-state
  **relative-angle** model (``theta_h_dot`` a known input, eq. (8)); the
  absolute 7-state model has an unobservable rigid-body mode with these two
  sensors (eigenvalue 0), see :mod:`._exo_design`.  The loop runs the
  steady-state discrete Kalman filter of the ZOH model; the margins and the
  Bode plot use the continuous Kalman-Bucy gain of eq. (9), same covariances;
- LQI with double integral action on the body torque, weights of eq. (15)
  (eq. (14) single-integral design reported alongside), gains against eqs. (16)-(17);
- test of Sec. 5.2: ``theta_h_dot = 0.1 rad/s`` from ``t = 0``, ``tau_ref``
  step of 10 N m at 0.1 s, 0.5 s; uniform noise within the bounds of Sec. 4
  on both inputs and both sensors (seeded).

Outputs: gains; gain, phase and delay margins of the loop broken at the motor
torque (Figs. 13-14); the -3 dB band of trunk velocity -> estimated body
torque (Fig. 15); the step test (Figs. 16-20): largest motor torque against
+-0.56 N m and the body-torque estimation error.

Run:  python -m reproductions.exo_lqi [OUTPUT_DIR]

References
----------
.. [1] Exoskeleton bond graph / Kalman observer paper,
   seed 004 (``docs/references.md``), Sections 3-5.
"""
from __future__ import annotations

import dataclasses
import sys
import tempfile
from pathlib import Path
from types import MappingProxyType

import numpy as np

from .errors import UnknownNameError
from plants.library.exoskeleton import PARAMETERS as EXO_PARAMETERS, exoskeleton
from bondgraph.params import Param
from estimators.lqi import lqi
from estimators.observer import continuous_kalman_gain
from fmus import export

from ._exo_analysis import band_limits, margins
from ._exo_design import NOISE_BOUNDS, PAPER_GAINS, PAPER_SIMULATION_PARAMS, Q_PRIME_C, R_PRIME_C, design, \
    disturbance_to_estimate, loop_at_plant_input, sampled_loop_at_plant_input
from ._exo_loop import NOISE_COLUMNS, cosimulate, monolithic

__all__ = ["NAME", "DESCRIPTION", "PARAMETERS", "SWEEP_METRICS", "FMU_FILES", "run", "simulate", "export_plant",
           "export_fmus", "noise"]

NAME = "exo-lqi"
DESCRIPTION = "exoskeleton (seed 004 Sec. 5.2) as FMU: Kalman observer + LQI with double integral action"

DT = 1e-4                #: controller / communication period, s
SEED = 2004              #: seed of the noise draw (numpy default_rng)
W_H = 0.1                #: trunk velocity, rad/s (Sec. 5.2)
TAU_REF, T_REF = 10.0, 0.1   #: reference step, N m at s (Sec. 5.2)
T_END, T_END_QUICK = 0.5, 0.2    #: horizon, s
MOTOR_TORQUE_LIMIT = 0.56        #: N m (Sec. 5.2)
#: FMU internal RK4 step, s: 0.05 / |fastest eigenvalue| (5.1e4 1/s, the motor-gear mode) rounded down
SOLVER_STEP = 5e-7
#: Sec. 5.2 of [1]_ (margins Figs. 13-14, bandwidth Fig. 15, errors Figs. 17 and 19).
PAPER = {"gains": dict(PAPER_GAINS), "margins": {"gain_db": 8.46, "phase_deg": 59.0, "delay_s": 0.007},
         "bandwidth_hz": 52.0, "most_destructive_band_hz": [4.0, 6.2], "estimation_mse": 0.1e-3,
         "motor_velocity_mse": 3e-6, "max_motor_torque_limit": MOTOR_TORQUE_LIMIT}
READING = ("relative angles (theta_h removed, theta_h_dot a known observer input): the absolute 7-state model "
           "is not detectable from motor velocity and sensor torque; LQI on (A1, Bm, Cb) of eqs. (10)-(12) with "
           "eq. (15) weights; noise bounds of Sec. 4 read as uniform on [-a, a] (variance a^2/3) for the "
           "Kalman covariances and the simulated noise; loop run at 0.1 ms with the discrete steady-state Kalman "
           "filter of the ZOH model (margins and Bode from the continuous Kalman-Bucy gain, eq. 9); bandwidth = "
           "upper -3 dB frequency below the peak (DC gain is 0 under double integral action); unpublished "
           "parameters from docs/exo-parameters.md (k_g, k_s, J_sint, J_sext assumed)")


#: What a run may vary (``run(params=...)``): every exoskeleton parameter (SI), defaults the
#: library's with the paper's simulation setting :data:`._exo_design.PAPER_SIMULATION_PARAMS`
#: (``b_f = 0``).  Plant FMU and controller design (LQI, Kalman gains) both take them: the design
#: follows the plant, as it would for a redesigned exoskeleton.
PARAMETERS = MappingProxyType({n: Param(n, PAPER_SIMULATION_PARAMS.get(n, p.value), p.unit, p.description)
                               for n, p in EXO_PARAMETERS.items()})
#: The main numbers, for sweep plots: margins (dB, deg, s), bandwidth (Hz), motor torque and
#: body-torque estimation error (N m).
SWEEP_METRICS = ("margins.gain_db", "margins.phase_deg", "margins.delay_s", "bandwidth_hz", "max_motor_torque",
                 "estimation_rms_Nm")
#: File name of the plant FMU in a ``fmu_dir`` (:func:`export_fmus`).
FMU_FILES = MappingProxyType({"plant": "exoskeleton.fmu"})


def noise(n: int, *, seed: int = SEED) -> np.ndarray:
    """Uniform noise within the bounds of Sec. 4 of [1]_, shape (n, 4), columns
    :data:`._exo_loop.NOISE_COLUMNS` (N m, rad/s, rad/s, N m)."""
    rng = np.random.default_rng(seed)
    bounds = np.array([NOISE_BOUNDS[c] for c in NOISE_COLUMNS])
    return rng.uniform(-1.0, 1.0, (n, len(NOISE_COLUMNS))) * bounds


def export_plant(path) -> Path:
    """The exoskeleton bond graph with the paper's simulation setting (``b_f = 0``) as an FMI 2.0
    FMU (internal RK4 step :data:`SOLVER_STEP`)."""
    return export(exoskeleton(params=dict(PAPER_SIMULATION_PARAMS)), path, solver_step=SOLVER_STEP)


def export_fmus(directory) -> dict:
    """Export the plant FMU into `directory` (``run(fmu_dir=directory)`` reuses it); returns
    ``{"plant": path}``."""
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    return {"plant": export_plant(directory / FMU_FILES["plant"])}


def simulate(*, quick: bool = False, dt: float = DT, seed: int = SEED, params=None, fmu_dir=None):
    """Design, export and co-simulate the step test.

    Parameters
    ----------
    quick : bool
        Horizon :data:`T_END_QUICK` instead of :data:`T_END`.
    dt : float, s
    seed : int
        Seed of the noise draw.
    params : mapping str -> float, optional
        Values (SI) of :data:`PARAMETERS` for plant and design.
    fmu_dir : path-like, optional
        Directory with the plant FMU of :func:`export_fmus` (exported there if missing).

    Returns
    -------
    design : ExoDesign
    result : CosimResult
    noise : ndarray, shape (n + 1, 4)
    """
    params = dict(params or {})
    unknown = sorted(set(params) - set(PARAMETERS))
    if unknown:
        raise UnknownNameError("parameter", unknown[0], PARAMETERS, f"scenario {NAME}")
    d = design(dt=dt, params=params)
    t_end = T_END_QUICK if quick else T_END
    n = int(round(t_end / dt))
    w = noise(n + 1, seed=seed)
    with tempfile.TemporaryDirectory() as tmp:
        fmu = Path(fmu_dir if fmu_dir is not None else tmp) / FMU_FILES["plant"]
        if not fmu.exists():
            fmu = export_fmus(fmu.parent)["plant"]
        res = cosimulate(d, fmu, t_end=n * dt, noise=w, w_h=W_H, tau_ref=TAU_REF, t_ref=T_REF,
                         params={k: float(v) for k, v in params.items()} or None)
    return d, res, w


def _gains(g) -> dict:
    out = {"Fix": [float(v) for v in g.Kx[0]], "Fiz_prime": float(g.Kz[0, 0])}
    if g.Kzz is not None:
        out["Fiz"] = float(g.Kzz[0, 0])
    return out


def _single_qz_1e13(d):
    """Single integral action (eqs. (10)-(11)) with the integral weight 1e13 instead of eq. (14)'s
    5e13: the reading under which eq. (17)'s F'_iz = -3.16 = -sqrt(1e13 / 1e12) follows (for single
    integral action F'_iz = -sqrt(q_z / R) whatever the plant)."""
    return lqi(d.A1, d.Bm, d.Cb, np.diag(Q_PRIME_C[:6] + (1e13,)), [[R_PRIME_C]], order=1)


def _as_dict(m) -> dict:
    return {"gain_db": m.gain_db, "phase_deg": m.phase_deg, "delay_s": m.delay_s,
            "w_gc_rad_s": m.w_gc, "w_pc_rad_s": m.w_pc}


def _other_margins(d) -> dict:
    """Margins of three other readings of the loop at the motor torque.

    ``state_feedback``: the LQ loop alone (true augmented state, no observer);
    ``motor_noise_observer``: Kalman-Bucy gain with process noise on the motor
    torque only (no trunk-velocity noise), which recovers the LQ loop
    (loop-transfer recovery at the plant input); ``sampled``: the discrete loop
    that runs in the co-simulation (ZOH plant, discrete filter, period ``dt``);
    ``printed_gains``: eqs. (16)-(17)'s printed gains with our plant and observer.
    """
    g = d.lqi2
    lq = margins(g.A_aug, g.B_aug, g.K, np.zeros((1, 1)))
    v = d.noise_var
    obs = continuous_kalman_gain(d.A1, d.Cm, np.diag([v["tau_m"], 0.0]), np.diag([v["w_m"], v["tau_s"]]),
                                 G=np.hstack([d.Bm, d.Bh]))
    ltr = margins(*loop_at_plant_input(dataclasses.replace(d, observer_c=obs)))
    sampled = margins(*sampled_loop_at_plant_input(d), dt=d.dt)
    # the printed gains of eqs. (16)-(17) with our (partly assumed) plant and Kalman gain
    Kx, Kz, Kzz = (np.atleast_2d(np.asarray(PAPER_GAINS[k], dtype=float)) for k in ("Fix", "Fiz_prime", "Fiz"))
    printed = dataclasses.replace(g, Kx=Kx, Kz=Kz, Kzz=Kzz, K=np.hstack([Kx, Kz, Kzz]))
    paper = margins(*loop_at_plant_input(dataclasses.replace(d, lqi2=printed)))
    return {"state_feedback": _as_dict(lq), "motor_noise_observer": _as_dict(ltr), "sampled": _as_dict(sampled),
            "printed_gains": _as_dict(paper)}


def run(plot_dir=None, *, quick: bool = False, params=None, seed: int = SEED, fmu_dir=None) -> dict:
    """The scenario's numbers (JSON-ready); Figs. 13-20 in `plot_dir` if given.

    `params` (values of :data:`PARAMETERS`, SI), `seed` (noise) and `fmu_dir`
    (reused plant FMU) as for :func:`simulate`.

    ``gains`` (eq. (15) design; ``single_integral`` the eq. (14) one;
    ``single_integral_qz_1e13`` the reading that gives eq. (17)'s F'_iz),
    ``margins`` (continuous loop at the motor-torque input with the
    Kalman-Bucy observer; ``margins_other_readings`` see
    :func:`_other_margins`), ``bandwidth_hz``
    (upper -3 dB frequency of trunk velocity -> estimated body torque; peak and
    lower limit in ``bode``), ``max_motor_torque`` (N m), ``estimation_mse``
    (mean of ``(y_b - y_b_hat)^2``, N^2 m^2, over the run), ``paper`` the
    published values, ``reading`` how the paper was read.
    """
    d, res, w = simulate(quick=quick, params=params, seed=seed, fmu_dir=fmu_dir)
    loop = loop_at_plant_input(d)
    mg = margins(*loop)
    dist = disturbance_to_estimate(d)
    band = band_limits(dist[0], dist[1], dist[2][[0]], dist[3][[0]])
    yb, ybh = np.asarray(res["plant.tau_b"]), np.asarray(res["ctrl.y_b_hat"])
    wm_true, wmh = np.asarray(res["plant.w_m"]), np.asarray(res["ctrl.w_m_hat"])
    u = np.asarray(res["ctrl.tau_m"])
    mono = monolithic(d, res.t, w, w_h=W_H, tau_ref=TAU_REF, t_ref=T_REF)
    settle = res.t >= res.t[-1] - 0.05
    result = {
        "gains": _gains(d.lqi2),
        "single_integral": _gains(d.lqi1),
        "single_integral_qz_1e13": _gains(_single_qz_1e13(d)),
        "margins": _as_dict(mg),
        "margins_other_readings": _other_margins(d),
        "bandwidth_hz": band.upper_hz,
        "bode": {"peak_hz": float(band.peak_hz), "peak_gain_db": float(20 * np.log10(band.peak_gain)),
                 "lower_hz": band.lower_hz, "upper_hz": band.upper_hz, "dc_gain": band.dc_gain},
        "max_motor_torque": float(np.max(np.abs(u))),
        "motor_torque_within_limit": bool(np.max(np.abs(u)) <= MOTOR_TORQUE_LIMIT),
        "estimation_mse": float(np.mean((yb - ybh) ** 2)),
        "estimation_rms_Nm": float(np.sqrt(np.mean((yb - ybh) ** 2))),
        "motor_velocity_mse": float(np.mean((wm_true - wmh) ** 2)),
        "body_torque_final_Nm": float(np.mean(yb[settle])),
        "body_torque_peak_Nm": float(np.max(yb)), "body_torque_min_Nm": float(np.min(yb)),
        "cosim_vs_monolithic_max_abs": {"tau_m": float(np.max(np.abs(u - mono["tau_m"]))),
                                        "y_b": float(np.max(np.abs(yb - mono["y_b"])))},
        "observer_poles_continuous": [float(np.min(d.observer_c.poles.real)),
                                      float(np.max(d.observer_c.poles.real))],
        "dt_s": d.dt, "t_end_s": float(res.t[-1]), "seed": int(seed),
        "params": {k: float(v) for k, v in dict(params or {}).items()}, "paper": PAPER, "reading": READING,
    }
    if plot_dir is not None:
        from ._exo_plots import plot_all
        plot_all(res, loop, mg, dist, band, plot_dir)
    return result


if __name__ == "__main__":
    import json
    print(json.dumps(run(sys.argv[1] if len(sys.argv) > 1 else "cosim-output"), indent=2))
