"""The demo's Monte-Carlo: the paper's UKF (``pam-ukf``) on rigs whose orifice areas and friction
vary by +-20 %, on a local Dask cluster, with its histogram of UKF vs model-alone angle RMSE."""
from __future__ import annotations

import os
import shutil
from pathlib import Path

__all__ = ["run_montecarlo", "VARY"]

#: What varies across the Monte-Carlo rigs (relative to the rig's own values, seed 000 Table II x
#: the rig's perturbation); the UKF keeps the nominal model.
VARY = {"A1": "uniform(0.8, 1.2)*nominal", "A2": "uniform(0.8, 1.2)*nominal",
        "c_s": "uniform(0.8, 1.2)*nominal", "mu_p": "uniform(0.8, 1.2)*nominal"}


def run_montecarlo(out: Path, *, quick: bool = False) -> dict:
    """16 runs (4 if `quick`) of ``pam-ukf`` on 13 segments of 1 s (0.3 s if `quick`), results and
    plots in ``out/montecarlo``; returns the files written."""
    from sweeps import montecarlo_spec, run_sweep

    samples, segment = (4, 0.3) if quick else (16, 1.0)
    workers = max(1, min(2, os.cpu_count() or 1))
    spec = montecarlo_spec("pam-ukf", samples=samples, vary=VARY, fixed={"segment_s": segment}, seed=2026,
                           metrics=["ukf.angle.I", "model_only.angle.I", "ukf.torque.I", "model_only.torque.I"])
    directory = Path(out) / "montecarlo"
    command = (f"bondcosim montecarlo pam-ukf --samples {samples} --set segment_s={segment} --seed 2026 "
               + " ".join(f"--vary '{k}={v}'" for k, v in VARY.items()) + f" --out {directory}")
    print(f"   same as: {command}")
    if directory.exists():                    # a demo starts afresh (a user's sweep would --resume)
        shutil.rmtree(directory)
    result = run_sweep(spec, directory, workers=workers)
    q = result.summary["quantiles"]
    print(f"   {result.summary['n_ok']} of {result.summary['n_runs']} runs ok on {result.stats.engine} in "
          f"{result.stats.wall_s:.1f} s; angle RMSE median UKF {q['ukf.angle.I']['q50']:.3g} deg "
          f"(5-95 %: {q['ukf.angle.I']['q05']:.3g}-{q['ukf.angle.I']['q95']:.3g}) vs model alone "
          f"{q['model_only.angle.I']['q50']:.3g} deg ({q['model_only.angle.I']['q05']:.3g}-"
          f"{q['model_only.angle.I']['q95']:.3g})")
    return {f"montecarlo:{key}": Path(path) for key, path in result.files.items()}
