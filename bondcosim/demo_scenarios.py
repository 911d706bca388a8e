"""The demo's closed-loop part: every registered paper scenario, its plots and a line of numbers."""
from __future__ import annotations

import time
from pathlib import Path

__all__ = ["run_scenarios", "summary_line"]

#: Scenarios the demo runs (``pam-pi`` has its own demo step), in the papers' order.
PAPER_SCENARIOS = ("pam-ukf", "pam-sensorless-pi", "kpid", "exo-lqi")


def _get(result: dict, *keys, default=None):
    for key in keys:
        if not isinstance(result, dict) or key not in result:
            return default
        result = result[key]
    return result


def summary_line(name: str, result: dict) -> str:
    """A one-line reading of scenario `name`'s result (the full numbers are in ``--json``)."""
    if name == "pam-ukf":
        parts = [f"{what} RMSE model-alone {_get(result, 'model_only', what, 'I'):.3g} -> "
                 f"UKF {_get(result, 'ukf', what, 'I'):.3g}" for what in ("angle", "torque")]
        return "; ".join(parts) + " (angle deg, torque N m)"
    if name == "pam-sensorless-pi":
        return ("steady-state tracking performance: angle "
                f"{_get(result, 'angle', 'steady_state_performance_pct'):.2f} %, torque "
                f"{_get(result, 'torque', 'steady_state_performance_pct'):.2f} % (paper 94.75 %, 95.0 %)")
    if name == "kpid":
        return (f"tracking precision PID {_get(result, 'pid', 'tracking_precision_pct'):.2f} %, "
                f"KPID {_get(result, 'kpid', 'tracking_precision_pct'):.2f} %; "
                + str(_get(result, "verdict", default="")))
    if name == "exo-lqi":
        m = result.get("margins", {})
        return (f"gains Fiz {_get(result, 'gains', 'Fiz'):.4g}, Fiz' {_get(result, 'gains', 'Fiz_prime'):.4g}; "
                f"margins {m.get('gain_db', float('nan')):.1f} dB, {m.get('phase_deg', float('nan')):.1f} deg, "
                f"{m.get('delay_s', float('nan')):.3g} s; bandwidth {result.get('bandwidth_hz', float('nan')):.2f} Hz; "
                f"max |motor torque| {result.get('max_motor_torque', float('nan')):.3f} N m")
    return ", ".join(f"{k} {v}" for k, v in result.items() if isinstance(v, (int, float)))


def run_scenarios(out: Path, *, quick: bool = False, step=print) -> dict:
    """Run the papers' scenarios that are registered, plots into `out`; returns the files written."""
    import reproductions as scenarios

    written = {}
    todo = [n for n in PAPER_SCENARIOS if n in scenarios.names()]
    for k, name in enumerate(todo, 1):
        step(f"[{k}/{len(todo)}] scenario {name}: {scenarios.describe(name)}")
        before = set(out.glob("*"))
        start = time.perf_counter()
        result = scenarios.run(name, out, quick=quick)
        print(f"   {summary_line(name, result)}")
        new = sorted(set(out.glob("*")) - before)
        print(f"   {len(new)} files in {time.perf_counter() - start:.1f} s")
        for path in new:
            written[f"{name}:{path.name}"] = path
    return written
