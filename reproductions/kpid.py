"""Scenario ``kpid``: seed 002 Section 3 -- one PAM (eq. (15)) under PID and under Kalman-PID.

The plant is eq. (15) of [1]_ exported as an FMU (continuous equivalent whose
zero-order hold at 1 ms is (15) exactly; :mod:`._kpid_plant`).  The loop, per
sample ``k`` (``T = 1 ms`` communication step, Fig. 1 of [1]_)::

    y_v(k) = y(k) + m(k)            measurement noise, mm
    u(k)   = controller(y_d(k), y_v(k))        PID or KPID, eq. (14)
    u_w(k) = u(k) + r(k)            process noise on the plant input
    plant:  y(k+1) from u_w held over [kT, (k+1)T]

with the paper's gains ``Kp = 25, Ki = 1e-6, Kd = 1e-3, T = 1 ms, Q = R = 1``
for both controllers (:data:`estimators.kpid.PAPER_SIMULATION`), references
``y_d = 20 cos(0.5 pi t) + 20`` (Table 1, 8 s) and ``y_d = 30`` (Table 2, 4 s),
plant at rest at ``y = 0``.

Reading of the paper (see :mod:`estimators.kpid` and ``docs/reproduction_kpid.md``)
- error ``e = y_d - y`` (eq. (14), model (5)); eq. (1)'s ``y - y_d`` is
  positive feedback on this plant (DC gain +27.8);
- the KPID filter's model (5) is discretised exactly (ZOH by the matrix
  exponential): the printed (7) is ``expm(-A T)``, the inverse of the transition
  matrix (entries near 7e10 with these gains), and its ``B21`` matches neither;
- noise "amplitude" 1 and 10: white Gaussian with that standard deviation
  (the uniform reading, on [-a, a], is reported as well); one seeded
  ``numpy.random.default_rng(SEED)`` draw shared by PID and KPID;
- the indicators (:mod:`._kpid_metrics`) on the **true** plant output ``y``;
  KPID's filtered output ``y_e`` and the noise-free loops are reported apart.

Run:  python -m reproductions.kpid [OUTPUT_DIR]

References
----------
.. [1] Yang H., Hao L., Chen Y., Xue B., "Kalman-PID control for chattering
   phenomena of bionic elbow joint actuated by pneumatic artificial muscles",
   Control Theory & Applications (2017); seed 002 (``docs/references.md``).
"""
from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import numpy as np

from estimators.kpid import KPID, PAPER_SIMULATION, PID
from fmus import export

from cosim.blocks import Function, Table
from cosim.component import Port, PythonBlock
from cosim.fmu_component import FMUComponent
from cosim.master import CoSimulation
from ._kpid_metrics import step_metrics, tracking_precision_pct
from ._kpid_plant import ARX_A, ARX_B, pam_single_equations
from .errors import ScenarioError

NAME = "kpid"
DESCRIPTION = "single PAM of seed 002 (eq. 15) as FMU: PID vs Kalman-PID under the paper's noise"

SEED = 2017                      #: seed of the noise draw (numpy default_rng)
PROCESS_NOISE = 1.0              #: "amplitude" of r(k), unit of u (Section 3 of [1])
MEASUREMENT_NOISE = 10.0         #: "amplitude" of m(k), mm
SOLVER_STEP = 5e-6               #: FMU internal RK4 step, s (RK4 error ~1e-11 relative)
#: Tables 1-2 of [1]_.
PAPER = {"pid": {"tracking_precision_pct": 3.75, "rise_time_s": 0.0171, "overshoot_pct": 0.0,
                 "settling_time_s": 0.0171, "steady_state_error_mm": 2.97},
         "kpid": {"tracking_precision_pct": 0.1, "rise_time_s": 0.005, "overshoot_pct": 0.0,
                  "settling_time_s": 0.005, "steady_state_error_mm": 0.04}}
READING = ("e = y_d - y (eq. 14 and model 5; eq. 1's sign is positive feedback); KPID model (5) "
           "discretised exactly by ZOH (printed eq. 7 is expm(-A T), unusable); filter update "
           "x+ = x- + M (y_v - C x- - y_d), P(0) = 0; gains Kp 25, Ki 1e-6, Kd 1e-3, T 1 ms, Q = R = 1 "
           "as printed; noise white Gaussian, std 1 on u and 10 mm on y (seeded); metrics on the true "
           "plant output y")


class Add(PythonBlock):
    """``y = a + b`` (direct feedthrough): adds a noise sample to a signal."""

    def __init__(self, name: str, unit: str = ""):
        super().__init__(name, inputs=[Port("a", unit), Port("b", unit)], outputs=[Port("y", unit)])

    def output(self, t: float) -> None:
        self.y[0] = self.u[0] + self.u[1]


class Controller(PythonBlock):
    """A :class:`~estimators.kpid.PID` or :class:`~estimators.kpid.KPID` as a block.

    Inputs ``r`` (reference :math:`y_d`, mm) and ``y_m`` (measurement :math:`y_v`, mm)
    feed through to ``u`` and ``y_e`` (the filtered output for KPID, ``y_m`` for
    PID).  The controller's state is committed in :meth:`advance`, so ``output``
    may be called more than once at one time (the master does at ``t0``).
    """

    def __init__(self, name: str, controller):
        self.controller = controller
        super().__init__(name, inputs=[Port("r", "mm", "reference y_d"),
                                       Port("y_m", "mm", "measured output y_v")],
                         outputs=[Port("u", "", "control"), Port("y_e", "mm", "filtered output")])
        self._committed = dict(vars(controller))

    def start(self, t0: float) -> None:
        self.controller.reset()
        self._committed = dict(vars(self.controller))

    def output(self, t: float) -> None:
        vars(self.controller).update(self._committed)      # the state at the start of this sample
        self.y[0] = self.controller.step(self.u[0], self.u[1])
        self.y[1] = getattr(self.controller, "filtered", self.u[1])

    def advance(self, t: float, dt: float) -> None:
        self._committed = dict(vars(self.controller))    # step() rebinds, never mutates, its arrays


def make_controller(kind: str):
    """``"pid"`` or ``"kpid"`` with the gains of Section 3 of [1]_."""
    p = PAPER_SIMULATION
    if kind == "pid":
        return PID(p["Kp"], p["Ki"], p["Kd"], T=p["T"])
    if kind == "kpid":
        return KPID(p["Kp"], p["Ki"], p["Kd"], T=p["T"], Q=p["Q"], R=p["R"])
    raise ScenarioError(f"controller kind must be 'pid' or 'kpid'; found {kind!r}")


def reference(kind: str):
    """Reference of Table 1 (``"periodic"``: 20 cos(0.5 pi t) + 20) or Table 2 (``"step"``: 30), mm."""
    if kind == "periodic":
        return lambda t: 20.0 * np.cos(0.5 * np.pi * t) + 20.0
    if kind == "step":
        return lambda t: 30.0
    raise ScenarioError(f"reference kind must be 'periodic' or 'step'; found {kind!r}")


def noise(n: int, *, seed: int = SEED, distribution: str = "gaussian", scale: float = 1.0):
    """Process noise ``r`` (on u) and measurement noise ``m`` (mm), ``n`` samples each.

    ``distribution``: ``"gaussian"`` (std = amplitude) or ``"uniform"`` (on [-a, a]);
    ``scale`` multiplies both (0: noise-free).
    """
    rng = np.random.default_rng(seed)
    if distribution == "gaussian":
        m, r = rng.normal(0.0, MEASUREMENT_NOISE, n), rng.normal(0.0, PROCESS_NOISE, n)
    elif distribution == "uniform":
        m = rng.uniform(-MEASUREMENT_NOISE, MEASUREMENT_NOISE, n)
        r = rng.uniform(-PROCESS_NOISE, PROCESS_NOISE, n)
    else:
        raise ScenarioError(f"distribution must be 'gaussian' or 'uniform'; found {distribution!r}")
    return scale * r, scale * m


def cosimulate(fmu, controller, yd, process, measurement, t_end: float):
    """One closed loop in the master: plant FMU, controller block, noise tables.

    Parameters
    ----------
    fmu : path-like
        The plant FMU (:func:`export_plant`).
    controller : PID or KPID
    yd : callable
        Reference, mm, a function of t (s).
    process, measurement : ndarray, shape (n + 1,)
        ``r(k)`` and ``m(k)`` at ``t_k = k T``, ``n = t_end / T``.
    t_end : float, s

    Returns
    -------
    CosimResult
        ``plant.y_mm`` (true output), ``meas.y`` (``y_v``), ``ctrl.u``, ``ctrl.y_e``,
        ``ref.y``, ``act.y`` (``u_w``).
    """
    T = PAPER_SIMULATION["T"]
    tk = np.arange(process.size) * T
    blocks = [Function("ref", yd, unit="mm"),
              Table("m", tk, measurement, unit="mm", interpolation="hold"),
              Table("r", tk, process, interpolation="hold"),
              Add("meas", "mm"), Add("act"), Controller("ctrl", controller),
              FMUComponent(fmu, "plant")]
    sim = CoSimulation(blocks, [
        ("plant.y_mm", "meas.a"), ("m.y", "meas.b"), ("ref.y", "ctrl.r"), ("meas.y", "ctrl.y_m"),
        ("ctrl.u", "act.a"), ("r.y", "act.b"), ("act.y", "plant.u")], step=T)
    return sim.run(t_end)


def monolithic(controller, yd, process, measurement) -> dict:
    """The same sampled loop with eq. (15) itself as the plant (no FMU): the reference
    the co-simulation is checked against.  Arrays ``y``, ``y_v``, ``u``, ``y_e``."""
    a, b = ARX_A, ARX_B
    n = process.size
    y, u = np.zeros(n + 3), np.zeros(n + 3)
    yv, ye = np.zeros(n), np.zeros(n)
    controller.reset()
    for k in range(n):
        i = k + 3
        y[i] = (a[0] * y[i - 1] + a[1] * y[i - 2] + a[2] * y[i - 3]
                + b[0] * u[i - 1] + b[1] * u[i - 2] + b[2] * u[i - 3])          # eq. (15)
        yv[k] = y[i] + measurement[k]
        uc = controller.step(yd[k], yv[k])
        ye[k] = getattr(controller, "filtered", yv[k])
        u[i] = uc + process[k]
    return {"y": y[3:], "y_v": yv, "u": u[3:] - process, "y_e": ye}


def export_plant(path) -> Path:
    """Write the plant FMU (FMI 2.0, internal RK4 step :data:`SOLVER_STEP`)."""
    return export(pam_single_equations(), path, solver_step=SOLVER_STEP)


def _indicators(case: str, t, y, yd) -> dict:
    if case == "periodic":
        return {"tracking_precision_pct": tracking_precision_pct(yd, y)}
    return step_metrics(t, y, 30.0)


def _loops(fmu, case: str, t_end: float, process, measurement) -> dict:
    yd = reference(case)
    return {kind: cosimulate(fmu, make_controller(kind), yd, process, measurement, t_end)
            for kind in ("pid", "kpid")}


def _table(loops_by_case, signal: str = "plant.y_mm") -> dict:
    out = {}
    for kind in ("pid", "kpid"):
        row = {}
        for case, loops in loops_by_case.items():
            res = loops[kind]
            sig = signal if kind == "kpid" or signal != "ctrl.y_e" else "meas.y"
            row.update(_indicators(case, res.t, res[sig], res["ref.y"]))
        out[kind] = row
    return out


def _paper_keys(row: dict) -> dict:
    return {k: row[k] for k in PAPER["pid"]}


def _verdict(table: dict) -> tuple[bool, str]:
    """KPID beats PID when it is better on every indicator of Tables 1-2 (None = not reached)."""
    pid, kpid = table["pid"], table["kpid"]
    wins, loses = [], []
    for key in PAPER["pid"]:
        a, b = kpid[key], pid[key]
        if a == b:
            continue
        better = b is None if a is None or b is None else (a is not None and a < b)
        (wins if better else loses).append(f"{key} {_fmt(a)} vs {_fmt(b)}")
    beats = not loses and bool(wins)
    text = (f"on the true plant output KPID {'beats' if beats else 'does NOT beat'} PID; KPID better: "
            f"{'; '.join(wins) or 'none'}; KPID worse: {'; '.join(loses) or 'none'} (KPID vs PID; "
            f"paper: KPID better on all)")
    return beats, text


def _fmt(v) -> str:
    return "not reached" if v is None else f"{v:.4g}"


def simulate(*, quick: bool = False) -> dict:
    """All loops of the scenario: ``{reading: {case: {controller: CosimResult}}}``.

    Readings ``"gaussian"`` (the main one), ``"uniform"`` and ``"noise_free"``;
    cases ``"periodic"`` (8 s, quick 1 s) and ``"step"`` (4 s, quick 0.5 s).
    """
    T = PAPER_SIMULATION["T"]
    durations = {"periodic": 1.0 if quick else 8.0, "step": 0.5 if quick else 4.0}
    out = {}
    with tempfile.TemporaryDirectory() as tmp:
        fmu = export_plant(Path(tmp) / "pam_single.fmu")
        for name, dist, scale in (("gaussian", "gaussian", 1.0), ("uniform", "uniform", 1.0),
                                  ("noise_free", "gaussian", 0.0)):
            out[name] = {}
            for case, t_end in durations.items():
                n = int(round(t_end / T))
                r, m = noise(n + 1, distribution=dist, scale=scale)
                out[name][case] = _loops(fmu, case, t_end, r, m)
    return out


def run(plot_dir=None, *, quick: bool = False) -> dict:
    """The scenario's numbers (JSON-ready); plots in `plot_dir` if given.

    ``pid``/``kpid`` hold the indicators of Tables 1-2 on the true plant output
    under the main reading (:data:`READING`); ``kpid_beats_pid`` and ``verdict``
    say whether KPID wins there; ``kpid_filtered_output`` gives KPID's
    indicators on its own filtered output ``y_e`` (the reading under which the
    paper's KPID row is approached); ``uniform_noise`` and ``noise_free`` the
    other noise readings; ``paper`` Tables 1-2.  ``None`` = not reached in the run.
    """
    loops = simulate(quick=quick)
    main = _table(loops["gaussian"])
    better, verdict = _verdict(main)
    ctrl = make_controller("kpid")
    for _ in range(50):                                       # the gain converges in a few steps
        ctrl.step(30.0, 0.0)
    result = {
        "pid": _paper_keys(main["pid"]), "kpid": _paper_keys(main["kpid"]), "reading": READING,
        "kpid_beats_pid": better, "verdict": verdict,
        "steady_state_bias_mm": {k: main[k]["steady_state_bias_mm"] for k in ("pid", "kpid")},
        "kpid_filtered_output": _paper_keys(_table(loops["gaussian"], "ctrl.y_e")["kpid"]),
        "uniform_noise": {k: _paper_keys(v) for k, v in _table(loops["uniform"]).items()},
        "noise_free": {k: _paper_keys(v) for k, v in _table(loops["noise_free"]).items()},
        "kalman_gain_MC": float((ctrl.gain.T @ ctrl.C.T).item()),
        "paper": PAPER, "seed": SEED,
        "t_end_s": {case: float(res["pid"].t[-1]) for case, res in loops["gaussian"].items()},
        "steps": int(sum(r.info["n_steps"] for rd in loops.values() for c in rd.values()
                         for r in c.values())),
    }
    if plot_dir is not None:
        _plot(loops, Path(plot_dir))
    return result


def _plot(loops, out: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    out.mkdir(parents=True, exist_ok=True)
    for case, title in (("periodic", "Fig. 3: y_d = 20 cos(0.5 pi t) + 20"), ("step", "Fig. 4: y_d = 30")):
        for reading in ("gaussian", "noise_free"):
            pid, kpid = loops[reading][case]["pid"], loops[reading][case]["kpid"]
            fig, (ax1, ax2) = plt.subplots(2, 1, sharex=True, figsize=(8, 6))
            t = pid.t
            ax1.plot(t, pid["ref.y"], "k--", lw=1, label="y_d")
            ax1.plot(t, pid["plant.y_mm"], lw=0.8, label="PID: y (true)")
            ax1.plot(t, kpid["plant.y_mm"], lw=0.8, label="KPID: y (true)")
            ax1.plot(t, kpid["ctrl.y_e"], lw=0.8, label="KPID: y_e (filtered)")
            ax1.set_ylabel("contraction, mm")
            ax1.set_title(f"seed 002 {title} ({reading.replace('_', '-')})")
            ax1.legend(loc="best", fontsize=8)
            ax2.plot(t, pid["ref.y"] - pid["plant.y_mm"], lw=0.8, label="PID: y_d - y")
            ax2.plot(t, kpid["ref.y"] - kpid["plant.y_mm"], lw=0.8, label="KPID: y_d - y")
            ax2.set_xlabel("t, s")
            ax2.set_ylabel("tracking error, mm")
            ax2.legend(loc="best", fontsize=8)
            fig.tight_layout()
            fig.savefig(out / f"kpid_{case}_{reading}.png", dpi=110)
            plt.close(fig)


if __name__ == "__main__":
    import json
    print(json.dumps(run(sys.argv[1] if len(sys.argv) > 1 else "cosim-output"), indent=2))
