"""Scenario ``pam-ukf``: UKF angle and torque estimation from the two pressures (seed 000, Secs. III-IV.A).

What the paper compares (Section IV-A, Figs. 9-10 of [1]_): the joint angle
:math:`\\psi` and torque :math:`\\tau` computed by the model alone (open loop,
from the valve commands) against those of a UKF that also uses the measured
pressures :math:`P_1, P_2` -- both against the rig's sensors -- with the
indices I (RMSE), M (max) and Q (M over the signal's range).

Here the "rig" is :mod:`._pam_rig`: the ``pam`` bond graph with perturbed
orifice areas, polytropic indexes and friction coefficients, exported as an
FMU and co-simulated in our master under a Fig. 8-like input profile
(:func:`plants.blockdiagram.pam.fig8_profile`, 13 segments of 10 s; quick:
0.3 s).  Per run:

1. **recording**: the rig FMU, at rest at :data:`U_PRE` before t = 0, driven by
   the profile (1 ms steps); truth ``psi`` (deg), ``tau`` (N m), and the pressure
   readings ``P1``, ``P2`` plus white Gaussian noise of :data:`SIGMA_P` (seeded);
2. **model alone**: the nominal ``pam`` (Table II) simulated open loop on the
   same inputs (the conventions' RK4, 4 sub-steps of 0.25 ms per sample);
3. **UKF**: :class:`estimators.UnscentedKalmanFilter` on the nominal model with
   the paper's :math:`P(0) = Q = \\mathrm{diag}(10^{-5}, 10^{-4}, 10^6, 10^6)`,
   :math:`R = \\mathrm{diag}(10^8, 10^8)`, Julier sigma points with
   :math:`\\kappa = 0`, measuring ``P1``, ``P2`` only;
   :math:`\\hat\\tau` is eq. (9) of the estimated state (Fig. 6).

Both estimators start from the same **wrong** state: the nominal model's rest
under the profile's first command (what one would assume), while the rig
rests under :data:`U_PRE`.

Reading of the paper (see ``docs/reproduction_pam_ukf.md``)
- angle on the free joint, torque with the joint locked at 0 deg (Section
  IV-A2: "the joint angle was fixed at 0 deg"); the locked UKF has the
  pressure states only, with the pressure block of the paper's P(0), Q;
- noise: :math:`\\sigma = \\sqrt{R_{ii}} = 10` kPa, so the filter's R is the
  true noise (and the E8F2 sensor's +-1 % of 1 MPa full scale);
- the indices are taken from :data:`T_CONVERGE` on: both estimates share the
  initial error by construction, so M over the whole record would be
  :math:`|z(0)|` for both; the whole-record values are under ``full_record``.

Run:  python -m reproductions.pam_ukf [OUTPUT_DIR]

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
from functools import lru_cache
from pathlib import Path
from types import MappingProxyType

import numpy as np

from plants.blockdiagram import pam as pam_bd
from plants.library.pam import FRICTION_STEP, PARAMETERS as PAM_PARAMETERS, parameter_values
from .errors import ParameterError, UnknownNameError
from bondgraph.params import Param
from bondgraph.numerics.simulation import simulate
from estimators import JulierSigmaPoints, UnscentedKalmanFilter
from estimators.ukf_model import StateMap

from cosim.blocks import Table
from cosim.fmu_component import FMUComponent
from cosim.master import CoSimulation
from ._pam_paper_ukf import KAPPA, PAPER_P0, PAPER_Q, PAPER_R, paper_state_map
from ._pam_rig import RIG_PERTURBATION, add_pressure_noise, export_rig, nominal_equations, rig_params, \
    rig_start_values
from ._pam_ukf_metrics import indices
from .errors import ScenarioError

__all__ = ["NAME", "DESCRIPTION", "PARAMETERS", "SWEEP_METRICS", "FMU_FILES", "run", "export_fmus", "inputs",
           "record_rig", "make_ukf", "ukf_estimates", "model_alone", "estimator_start", "experiment",
           "PAPER_OFFLINE"]

NAME = "pam-ukf"
DESCRIPTION = "UKF estimating PAM joint angle and torque from P1, P2 on a perturbed rig FMU (seed 000)"

SAMPLE_TIME = 1e-3                    # s, the rig's sampling period (Sec. II-A of [1])
SEGMENT, QUICK_SEGMENT = 10.0, 0.3    # s, length of each of the 13 Fig. 8-like segments
U_PRE = (5.0, 5.0)                    # V, valve commands the rig rests under before t = 0
SIGMA_P = 1e4                         # Pa, pressure-sensor noise (std) = sqrt(R_ii)
SEED = 5                              # numpy.random.default_rng seed of the noise
T_CONVERGE = 1.0                      # s, indices from here on (after the shared initial error)


def _parameters():
    rig = rig_params()
    table = {n: Param(n, rig[n], p.unit, f"rig: {p.description}"
                      + (f" x{RIG_PERTURBATION[n]:g}" if n in RIG_PERTURBATION else ""))
             for n, p in PAM_PARAMETERS.items()}
    table["segment_s"] = Param("segment_s", SEGMENT, "s", "length of each of the 13 input-profile segments "
                               f"(quick: {QUICK_SEGMENT})")
    table["sigma_p"] = Param("sigma_p", SIGMA_P, "Pa", "pressure-sensor noise (std)")
    return MappingProxyType(table)


#: What a run may vary (``run(params=...)``): every ``pam`` parameter of the rig (SI; the
#: default is the rig's value, Table II times :data:`RIG_PERTURBATION`), ``segment_s`` and
#: ``sigma_p``.  The estimators keep the nominal Table II model whatever the rig.
PARAMETERS = _parameters()

#: The main numbers, for sweep plots: angle and torque RMSE (index I; deg, N m), UKF and model alone.
SWEEP_METRICS = ("ukf.angle.I", "model_only.angle.I", "ukf.torque.I", "model_only.torque.I")

#: Section IV-A of [1]: offline estimation (Figs. 9, 10), angle in deg, torque in N m.
PAPER_OFFLINE = {
    "model_only": {"angle": {"I": 1.053, "M": 3.50, "Q": 0.0887}, "torque": {"I": 0.162, "M": 0.494, "Q": 0.1023}},
    "ukf": {"angle": {"I": 0.838, "M": 2.42, "Q": 0.0613}, "torque": {"I": 0.108, "M": 0.238, "Q": 0.0494}},
}


def inputs(*, quick: bool = False):
    """The Fig. 8-like valve commands, 1 ms samples.

    Parameters
    ----------
    quick : bool
        13 segments of :data:`QUICK_SEGMENT` (3.9 s) instead of :data:`SEGMENT`
        (130 s, the paper's N = 130e3).

    Returns
    -------
    t : ndarray, shape (n,), s
    u : ndarray, shape (n, 2), V
    """
    return pam_bd.fig8_profile(segment=QUICK_SEGMENT if quick else SEGMENT)


def record_rig(fmu, t, u, *, locked: bool = False, u_pre=U_PRE, params=None) -> dict:
    """Co-simulate the rig FMU in the master under the commands `u`.

    Parameters
    ----------
    fmu : path-like
        From :func:`._pam_rig.export_rig` (with the same `locked`).
    t : ndarray, shape (n,), s
        ``0, 1 ms, ...``; the run ends at ``t[-1]``.
    u : ndarray, shape (n, 2), V
        Row k held over ``[t_k, t_k + 1 ms)`` (Table blocks, zero-order hold).
    locked : bool
    u_pre : (float, float), V
        Commands the rig rests under before t = 0 (:func:`._pam_rig.rig_start_values`).
    params : mapping str -> float, optional
        Rig parameter values (SI) set on the FMU before initialisation (default:
        its own start values, :func:`._pam_rig.rig_params`).

    Returns
    -------
    dict str -> ndarray, shape (n,)
        ``t`` (s), ``psi`` (deg), ``P1``, ``P2`` (Pa abs), ``tau`` (N m): the rig's truth.

    Raises
    ------
    ValueError
        `t` not 0, 1 ms, 2 ms, ...; `u` not of shape (len(t), 2) or not finite.
    """
    t, u = _profile(t, u, "record_rig")
    values = rig_params(params)
    plant = FMUComponent(fmu, "rig", start_values=rig_start_values(u_pre, locked=locked, params=values),
                         parameters={n: values[n] for n in nominal_equations(locked=locked).param_names})
    tables = [Table(f"u{i}", t, u[:, i - 1], unit="V", interpolation="hold") for i in (1, 2)]
    sim = CoSimulation(tables + [plant], [("u1.y", "rig.u1"), ("u2.y", "rig.u2")], step=SAMPLE_TIME)
    result = sim.run(float(t[-1]))
    return {"t": result.t, **{s: np.array(result[f"rig.{s}"]) for s in ("psi", "P1", "P2", "tau")}}


def _profile(t, u, who: str):
    """`t`, `u` as float arrays; u of shape (len(t), 2), t = 0, 1 ms, 2 ms, ..."""
    t, u = np.asarray(t, dtype=float), np.asarray(u, dtype=float)
    if t.ndim != 1 or t.size < 2 or u.shape != (t.size, 2):
        raise ScenarioError(f"{who}: need t of shape (n >= 2,) and u of shape (n, 2) (V); found t {t.shape}, "
                         f"u {u.shape}")
    if not np.allclose(t, np.arange(t.size) * SAMPLE_TIME, rtol=0.0, atol=1e-9):
        raise ScenarioError(f"{who}: t must be 0, 1 ms, 2 ms, ... (the rig's sampling)")
    if not np.all(np.isfinite(u)):
        raise ScenarioError(f"{who}: u has non-finite values (first at row {int(np.argmax(~np.isfinite(u).all(1)))})")
    return t, u


@lru_cache(maxsize=1)
def _state_map() -> StateMap:
    """The paper's :math:`x = (\\psi, \\dot\\psi, P_1, P_2)` over the model's states (p_J = J psi')."""
    return paper_state_map(nominal_equations().state_names, parameter_values()["J"])


def estimator_start(u0, *, locked: bool = False) -> np.ndarray:
    """Initial estimate: the nominal model at rest under commands `u0`.

    Parameters
    ----------
    u0 : array_like, shape (2,), V
    locked : bool

    Returns
    -------
    ndarray
        ``(psi [rad], dpsi [rad/s], P1 [Pa], P2 [Pa])``, or ``(P1, P2)`` if `locked`.
    """
    x = pam_bd.equilibrium(np.asarray(u0, dtype=float), variant="locked" if locked else "full")
    return x[2:] if locked else x


def make_ukf(x0, *, locked: bool = False) -> UnscentedKalmanFilter:
    """The paper's UKF on the nominal ``pam`` (or ``pam-locked``), measuring ``P1``, ``P2``.

    Parameters
    ----------
    x0 : array_like, shape (4,) or (2,) if locked
        :math:`\\hat x(0)`: ``(psi [rad], dpsi [rad/s], P1 [Pa], P2 [Pa])`` or ``(P1, P2)``.
    locked : bool
        The locked joint: states ``P_1``, ``P_2`` only; P(0) and Q are the
        pressure block of the paper's.

    Returns
    -------
    UnscentedKalmanFilter
        1 ms samples of 4 RK4 sub-steps, Julier points with :math:`\\kappa = 0`.
    """
    keep = slice(2, 4) if locked else slice(0, 4)
    n = 2 if locked else 4
    return UnscentedKalmanFilter.from_model(
        nominal_equations(locked=locked), dt=SAMPLE_TIME, substeps=round(SAMPLE_TIME / FRICTION_STEP), outputs=("P1", "P2"),
        x0=x0, P0=PAPER_P0[keep, keep], Q=PAPER_Q[keep, keep], R=PAPER_R,
        points=JulierSigmaPoints(n, kappa=KAPPA), state_map=None if locked else _state_map())


def ukf_estimates(z, u, x0, *, locked: bool = False) -> dict:
    """Run the UKF of :func:`make_ukf` over a recording.

    Parameters
    ----------
    z : ndarray, shape (n, 2), Pa
        Pressure readings ``(P1, P2)``; row 0 is not used (the paper's recursion).
    u : ndarray, shape (n, 2), V
        Commands, row k held over sample k.
    x0 : array_like
        :math:`\\hat x(0)` (:func:`estimator_start`).
    locked : bool

    Returns
    -------
    dict str -> ndarray, shape (n,)
        ``psi`` (deg), ``P1``, ``P2`` (Pa), ``tau`` (N m, eq. (9) of the estimate, Fig. 6).
    """
    ukf = make_ukf(x0, locked=locked)
    est = ukf.batch_filter(z, u)
    x_model = est.x if locked else _state_map().to_model(est.x)
    y = ukf.model.h(x_model, np.asarray(u, dtype=float))
    names = list(ukf.model.output_names)
    return {s: y[:, names.index(s)] for s in ("psi", "P1", "P2", "tau")}


def model_alone(t, u, x0, *, locked: bool = False) -> dict:
    """The nominal model open loop on the commands: the paper's "estimation by model".

    Parameters
    ----------
    t : ndarray, shape (n,), s
    u : ndarray, shape (n, 2), V
    x0 : array_like
        Initial state as for :func:`make_ukf`.
    locked : bool

    Returns
    -------
    dict str -> ndarray, shape (n,)
        ``psi`` (deg), ``P1``, ``P2`` (Pa), ``tau`` (N m).

    Raises
    ------
    ValueError
        As :func:`record_rig`.
    """
    t, u = _profile(t, u, "model_alone")
    eqs = nominal_equations(locked=locked)
    x_model = np.asarray(x0, dtype=float) if locked else _state_map().to_model(x0)
    res = simulate(eqs, (0.0, float(t[-1])), inputs={"u1": (t, u[:, 0]), "u2": (t, u[:, 1])},
                   x0=dict(zip(eqs.state_names, x_model)), method="RK4", dt=FRICTION_STEP,
                   output_interval=SAMPLE_TIME)
    return {s: np.array(res[s]) for s in ("psi", "P1", "P2", "tau")}


def experiment(fmu, t, u, rng, *, locked: bool = False, params=None, sigma_p: float = SIGMA_P) -> dict:
    """Recording, noisy pressures, model alone and UKF for one rig variant.

    Parameters
    ----------
    fmu : path-like
        The rig FMU (:func:`._pam_rig.export_rig` with the same `locked`).
    t : ndarray, shape (n,), s
    u : ndarray, shape (n, 2), V
    rng : numpy.random.Generator
        Draws the pressure noise.
    locked : bool
    params : mapping str -> float, optional
        Rig parameter values (SI) overriding :func:`._pam_rig.rig_params`.
    sigma_p : float, Pa
        Pressure-noise standard deviation (default :data:`SIGMA_P`).

    Returns
    -------
    dict
        ``t``, ``u``, ``truth``, ``model``, ``ukf`` (dicts of signals, see
        :func:`record_rig`) and ``z`` (shape (n, 2), Pa: the noisy readings).
    """
    truth = record_rig(fmu, t, u, locked=locked, params=params)
    z = add_pressure_noise(np.column_stack([truth["P1"], truth["P2"]]), rng, sigma_p)
    x0 = estimator_start(u[0], locked=locked)
    return {"t": t, "u": u, "truth": truth, "z": z, "model": model_alone(t, u, x0, locked=locked),
            "ukf": ukf_estimates(z, u, x0, locked=locked)}


def _scores(runs: dict, start: int) -> dict:
    keys = {"angle": ("free", "psi"), "torque": ("locked", "tau")}
    return {method: {q: indices(runs[v]["truth"][s][start:], runs[v][method][s][start:])
                     for q, (v, s) in keys.items()} for method in ("model", "ukf")}


#: File names of the rig FMUs in a ``fmu_dir`` (:func:`export_fmus`).
FMU_FILES = MappingProxyType({"free": "pam_rig.fmu", "locked": "pam_rig_locked.fmu"})


def export_fmus(directory) -> dict:
    """Export the two rig FMUs (free joint, locked joint) into `directory`.

    ``run(fmu_dir=directory)`` then reuses them: a sweep builds them once and
    ships the files to its workers; each run sets its own rig parameters as
    FMU parameters before initialisation.

    Returns
    -------
    dict str -> pathlib.Path
        ``{"free": ..., "locked": ...}``, the names of :data:`FMU_FILES`.
    """
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    return {v: export_rig(directory / name, locked=v == "locked") for v, name in FMU_FILES.items()}


def _split(params, quick: bool):
    """(rig overrides, segment s, sigma Pa) from `params`, every name checked."""
    params = dict(params or {})
    unknown = sorted(set(params) - set(PARAMETERS))
    if unknown:
        raise UnknownNameError("parameter", unknown[0], PARAMETERS, f"scenario {NAME}")
    segment = float(params.pop("segment_s", QUICK_SEGMENT if quick else SEGMENT))
    sigma = float(params.pop("sigma_p", SIGMA_P))
    if not np.isfinite(segment) or 13 * segment < 2 * T_CONVERGE:
        raise ParameterError(f"scenario {NAME}: segment_s = {segment!r} s is too short; the 13 segments must "
                             f"last at least 2 T_CONVERGE = {2 * T_CONVERGE} s", name="segment_s")
    return params, segment, sigma


def run(plot_dir=None, *, quick: bool = False, params=None, seed: int = SEED, fmu_dir=None) -> dict:
    """The scenario's numbers (JSON-ready); plots in `plot_dir` if given.

    Parameters
    ----------
    plot_dir : path-like, optional
    quick : bool
        Segments of :data:`QUICK_SEGMENT` instead of :data:`SEGMENT` (unless
        ``params`` sets ``segment_s``).
    params : mapping str -> float, optional
        Values (SI) of :data:`PARAMETERS` replacing their defaults: the rig's
        parameters (the estimators keep the nominal model), ``segment_s``, ``sigma_p``.
    seed : int
        Seed of the pressure noise (``numpy.random.default_rng``).
    fmu_dir : path-like, optional
        Directory holding the rig FMUs of :func:`export_fmus` (exported there if
        missing); default: exported into a temporary directory for this run.

    Returns
    -------
    dict
        ``{"model_only": {"angle": {"I", "M", "Q"}, "torque": {...}}, "ukf": {...}}``
        (angle I, M in deg, torque I, M in N m, Q ratio) over ``t >=``
        :data:`T_CONVERGE`; alongside: ``full_record`` (same indices over k = 0..N),
        ``second_half`` (over the second half of the record, long after the
        initial error: what model mismatch and filter alone give),
        ``paper`` (:data:`PAPER_OFFLINE`), ``ranges``, ``units``, ``window_s``,
        ``perturbation``, ``params`` (the overrides), ``noise_sigma_pa``, ``seed``, ``quick``.

    Raises
    ------
    UnknownNameError
        A parameter not in :data:`PARAMETERS` (the message lists them).
    ParameterError
        A value that is not a finite number, or ``segment_s`` too short.
    """
    rig, segment, sigma = _split(params, quick)
    t, u = pam_bd.fig8_profile(segment=segment)
    rng = np.random.default_rng(seed)
    runs = {}
    with tempfile.TemporaryDirectory() as tmp:
        where = Path(fmu_dir) if fmu_dir is not None else Path(tmp)
        fmus = {v: where / name for v, name in FMU_FILES.items()}
        if not all(f.exists() for f in fmus.values()):
            fmus = export_fmus(where)
        for variant in ("free", "locked"):
            runs[variant] = experiment(fmus[variant], t, u, rng, locked=variant == "locked", params=rig,
                                       sigma_p=sigma)
    start = int(round(T_CONVERGE / SAMPLE_TIME))
    half = (t.size - 1) // 2
    late, full, second = _scores(runs, start), _scores(runs, 0), _scores(runs, half)
    out = {"model_only": late["model"], "ukf": late["ukf"],
           "full_record": {"model_only": full["model"], "ukf": full["ukf"]},
           "second_half": {"window_s": [float(t[half]), float(t[-1])],
                           "model_only": second["model"], "ukf": second["ukf"]},
           "paper": PAPER_OFFLINE,
           "ranges": {"angle_deg": [float(runs["free"]["truth"]["psi"][start:].min()),
                                    float(runs["free"]["truth"]["psi"][start:].max())],
                      "torque_nm": [float(runs["locked"]["truth"]["tau"][start:].min()),
                                    float(runs["locked"]["truth"]["tau"][start:].max())]},
           "units": {"angle": "deg", "torque": "N m", "Q": "1"},
           "window_s": [T_CONVERGE, float(t[-1])], "perturbation": dict(RIG_PERTURBATION),
           "params": {k: float(v) for k, v in dict(params or {}).items()},
           "noise_sigma_pa": sigma, "seed": int(seed), "quick": quick}
    if plot_dir is not None:
        from ._pam_ukf_plots import save_plots
        save_plots(runs, Path(plot_dir), t_converge=T_CONVERGE)
    return out


if __name__ == "__main__":
    print(json.dumps(run(sys.argv[1] if len(sys.argv) > 1 else "cosim-output"), indent=1))
