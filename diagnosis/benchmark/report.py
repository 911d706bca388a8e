"""Summary, tables and plot of a benchmark run."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

__all__ = ["summarise", "write_report", "markdown", "TARGETS"]

#: The issue's targets: kind right, place right, held-out halved (non-null cases), false alarms (nulls).
TARGETS = {"kind_right": 0.90, "place_right": 0.85, "holdout_halved": 0.90, "false_alarms": 0.05}


def _share(flags):
    flags = list(flags)
    return float(np.mean(flags)) if flags else float("nan")


def summarise(results: list[dict]) -> dict:
    """Headline rates, the confusion matrix of kinds and per-kind / per-plant rates."""
    scored = [r for r in results if "generator_error" not in r]
    effects = [r for r in scored if r["kind"] != "none"]
    nulls = [r for r in scored if r["kind"] == "none"]
    imp = [r["improvement"] for r in effects]
    halved = [bool(np.isfinite(v) and v >= 0.5) for v in imp]
    drift = [r for r in effects if r.get("drifting_plant") or r.get("nominal_drifts")]
    secs = [r["seconds_diagnose"] for r in scored]
    headline = {
        "cases": len(results), "scored": len(scored), "generator_errors": len(results) - len(scored),
        "effect_cases": len(effects), "null_cases": len(nulls), "drifting_cases": len(drift),
        # held-out errors measured by the segment simulation error (diagnosis.segments), not open-loop
        "segment_judged": sum(1 for r in scored if r.get("judge") == "segments"),
        "kind_right": _share(r["kind_ok"] for r in effects),
        # a separate measure: the concealed kind is the answer's or one the recording cannot tell apart
        # from it (diagnosis.alternatives); over the cases scored with it (older case files lack it)
        "kind_right_or_indistinguishable": _share(r["kind_or_indistinguishable_ok"] for r in effects
                                                  if "kind_or_indistinguishable_ok" in r),
        "place_right": _share(r["place_ok"] for r in effects),
        "holdout_halved": _share(halved),
        "false_alarms": _share(not r["kind_ok"] for r in nulls),
        "diagnosis_errors": sum(1 for r in scored if r["answer_kind"] == "error"),
        # cases whose recording has a sensor's glitches (diagnosis.benchmark.run.glitches), and how many of
        # them were answered right (kind right; for a null, no false alarm)
        "glitchy_cases": sum(1 for r in scored if r.get("glitches")),
        "glitchy_right": sum(1 for r in scored if r.get("glitches") and r["kind_ok"]),
        **_compound_headline(effects),
        **_detuned_headline(scored),
        **_sampling_headline(scored),
        "seconds_per_case_median": float(np.median(secs)) if secs else float("nan"),
        "seconds_per_case_max": float(np.max(secs)) if secs else float("nan"),
    }
    kinds = sorted({r["kind"] for r in scored} | {r["answer_kind"] for r in scored})
    confusion = {k: {a: 0 for a in kinds} for k in kinds}
    for r in scored:
        confusion[r["kind"]][r["answer_kind"]] += 1

    def group(key):
        out = {}
        for r in scored:
            g = out.setdefault(r[key], {"n": 0, "kind": [], "place": [], "halved": []})
            g["n"] += 1
            g["kind"].append(r["kind_ok"])
            g["place"].append(r["place_ok"])
            if r["kind"] != "none":
                g["halved"].append(bool(np.isfinite(r["improvement"]) and r["improvement"] >= 0.5))
        return {k: {"n": v["n"], "kind_right": _share(v["kind"]), "place_right": _share(v["place"]),
                    "holdout_halved": _share(v["halved"])} for k, v in sorted(out.items())}

    return {"headline": headline, "confusion": confusion, "by_kind": group("kind"),
            "by_plant": group("plant"),
            "improvement_quantiles": {q: float(np.nanquantile(imp, q)) if imp else float("nan")
                                      for q in (0.1, 0.25, 0.5, 0.75, 0.9)}}


def _detuned_headline(scored: list) -> dict:
    """Of the cases with a detuned nominal (``--detune``): how many, and the share whose answers
    refitted the detuned value (``nominal_value``)."""
    detuned = [r for r in scored if r.get("detuned")]
    if not detuned:
        return {}
    return {"detuned_cases": len(detuned), "detuned_named": _share(r["detuned_named"] for r in detuned)}


def _sampling_headline(scored: list) -> dict:
    """Of the cases recorded at a scaled rate and length (``--sampling``): how many, and the
    smallest and largest factors drawn."""
    drawn = [r["sampling"] for r in scored if r.get("sampling")]
    if not drawn:
        return {}
    return {"resampled_cases": len(drawn),
            "rate_factors": [min(d["rate_factor"] for d in drawn), max(d["rate_factor"] for d in drawn)],
            "duration_factors": [min(d["duration_factor"] for d in drawn),
                                 max(d["duration_factor"] for d in drawn)]}


def _compound_headline(effects: list) -> dict:
    """Of the compound cases (a second concealed effect, ``--compound``): how many, and the share
    in which some answered effect names the first's kind, the second's, and both (each at one of
    its places, or its kind listed as not told apart there), each share over the cases where the
    effects it asks for are visible in the truth with both (effect-to-noise at least the draw's
    least, :func:`~diagnosis.benchmark.compound.visibility`; a case scored before the measure
    existed counts as visible); nothing for a run without them."""
    from .draw import RATIOS
    compound = [r for r in effects if r.get("also_kind")]
    if not compound:
        return {}

    def seen(r, key):
        return not r.get(key, np.nan) < RATIOS[0]     # NaN: not measured, counted

    first = [r for r in compound if seen(r, "first_visible")]
    second = [r for r in compound if seen(r, "also_visible")]
    both = [r for r in first if seen(r, "also_visible")]
    return {"compound_cases": len(compound), "second_visible": len(second), "both_visible": len(both),
            "first_found": _share(r["first_found"] for r in first),
            "second_found": _share(r["also_found"] for r in second),
            "both_found": _share(r["first_found"] and r["also_found"] for r in both)}


def _pct(x):
    return "-" if not np.isfinite(x) else f"{100 * x:.0f} %"


def markdown(summary: dict, *, seed: int | None = None) -> str:
    """The tables as Markdown (for docs/diagnosis.md)."""
    h = summary["headline"]
    lines = [f"Benchmark: {h['cases']} cases (seed {seed}), {h['effect_cases']} with an effect "
             f"({h['drifting_cases']} on a drifting nominal), {h['null_cases']} nulls; "
             f"{h.get('segment_judged', 0)} judged by the segment simulation error; "
             f"{h['generator_errors']} generator errors, {h['diagnosis_errors']} diagnosis errors; "
             f"{h.get('glitchy_cases', 0)} recordings with a sensor's glitches, {h.get('glitchy_right', 0)} of them "
             "answered right.", "",
             "| measure | result | target |", "|---|---|---|",
             f"| kind right (effect cases) | {_pct(h['kind_right'])} | >= 90 % |",
             f"| kind right or among the stated indistinguishable alternatives (effect cases) | "
             f"{_pct(h.get('kind_right_or_indistinguishable', float('nan')))} | |",
             f"| place right or equivalent (effect cases) | {_pct(h['place_right'])} | >= 85 % |",
             f"| held-out NRMSE of the affected output at least halved | {_pct(h['holdout_halved'])} | >= 90 % |",
             f"| false alarms on nulls | {_pct(h['false_alarms'])} | <= 5 % |",
             *([f"| compound cases ({h['compound_cases']}, two concealed effects; the second visible in "
                f"{h.get('second_visible', h['compound_cases'])}, both in {h.get('both_visible', h['compound_cases'])})"
                f": some answer names the first / the second / both | {_pct(h['first_found'])} / "
                f"{_pct(h['second_found'])} / {_pct(h['both_found'])} | |"] if "compound_cases" in h else []),
             *([f"| nominal detuned ({h['detuned_cases']} cases, one storage value): the value refitted "
                f"(nominal_value) | {_pct(h['detuned_named'])} | |"] if "detuned_cases" in h else []),
             *([f"| recorded at another rate and length ({h['resampled_cases']} cases): rate x "
                f"{h['rate_factors'][0]:.2f}-{h['rate_factors'][1]:.2f}, duration x "
                f"{h['duration_factors'][0]:.2f}-{h['duration_factors'][1]:.2f} | | |"] if "resampled_cases" in h else []),
             f"| time per case, median / max | {h['seconds_per_case_median']:.0f} s / "
             f"{h['seconds_per_case_max']:.0f} s | |", "",
             "| held-out improvement quantile | " + " | ".join(f"{int(q * 100)} %" for q in
                                                         summary["improvement_quantiles"]) + " |",
             "|---" * (1 + len(summary["improvement_quantiles"])) + "|",
             "| 1 - improved / nominal | " + " | ".join(_pct(v) for v in
                                                     summary["improvement_quantiles"].values()) + " |", "",
             "| kind | cases | kind right | place right | held-out halved |", "|---|---|---|---|---|"]
    for k, v in summary["by_kind"].items():
        lines.append(f"| {k} | {v['n']} | {_pct(v['kind_right'])} | {_pct(v['place_right'])} | "
                     f"{_pct(v['holdout_halved'])} |")
    lines += ["", "| plant | cases | kind right | place right | held-out halved |", "|---|---|---|---|---|"]
    for k, v in summary["by_plant"].items():
        lines.append(f"| {k} | {v['n']} | {_pct(v['kind_right'])} | {_pct(v['place_right'])} | "
                     f"{_pct(v['holdout_halved'])} |")
    conf = summary["confusion"]
    kinds = list(conf)
    lines += ["", "Confusion matrix (rows: concealed kind, columns: the answer's first kind):", "",
              "| truth \\ answer | " + " | ".join(kinds) + " |", "|---" * (len(kinds) + 1) + "|"]
    for k in kinds:
        lines.append(f"| {k} | " + " | ".join(str(conf[k][a] or "") for a in kinds) + " |")
    return "\n".join(lines) + "\n"


def write_report(results: list[dict], summary: dict, outdir, *, seed=None) -> None:
    """``results.json``, ``results.md`` and ``results.png`` in `outdir`."""
    out = Path(outdir)
    out.mkdir(parents=True, exist_ok=True)
    (out / "results.json").write_text(json.dumps({"seed": seed, "summary": summary,
                                                  "cases": sorted(results, key=lambda r: r["label"])},
                                                 indent=1, default=float))
    (out / "results.md").write_text(markdown(summary, seed=seed))
    plot(results, summary, out / "results.png")


def plot(results, summary, path) -> None:
    """Confusion matrix, distribution of held-out improvement, time per case."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    conf = summary["confusion"]
    kinds = list(conf)
    m = np.array([[conf[k][a] for a in kinds] for k in kinds], float).reshape(len(kinds), len(kinds))
    fig, ax = plt.subplots(1, 3, figsize=(17, 6), gridspec_kw={"width_ratios": [2.2, 1, 1]})
    if not kinds:           # no case scored (every one a generator error): the panels stay empty
        ax[0].text(0.5, 0.5, "no case scored", ha="center", va="center", transform=ax[0].transAxes)
    ax[0].imshow(m if kinds else np.zeros((1, 1)), cmap="Blues")
    ax[0].set_xticks(range(len(kinds)), kinds, rotation=70, fontsize=7)
    ax[0].set_yticks(range(len(kinds)), kinds, fontsize=7)
    for i in range(len(kinds)):
        for j in range(len(kinds)):
            if m[i, j]:
                ax[0].text(j, i, int(m[i, j]), ha="center", va="center", fontsize=7,
                           color="white" if m[i, j] > m.max() / 2 else "black")
    ax[0].set_xlabel("answer (first effect)")
    ax[0].set_ylabel("concealed kind")
    ax[0].set_title("kinds")
    imp = np.array([r["improvement"] for r in results if r.get("kind", "none") != "none"
                    and "generator_error" not in r], float)
    imp = np.clip(imp[np.isfinite(imp)], -1.0, 1.0)
    ax[1].hist(imp, bins=np.linspace(-1, 1, 21), color="tab:green")
    ax[1].axvline(0.5, color="k", ls="--", lw=1)
    ax[1].set_xlabel("held-out improvement 1 - NRMSE_improved / NRMSE_nominal (clipped at -1)")
    ax[1].set_ylabel("effect cases")
    ax[1].set_title("affected output, held-out part")
    secs = [r["seconds_diagnose"] for r in results if "generator_error" not in r]
    ax[2].hist(secs, bins=20, color="tab:gray")
    ax[2].set_xlabel("diagnosis time per case, s")
    ax[2].set_title("time")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
