"""The result of a diagnosis: JSON in the issue's schema, plain-language text, plots, improved graph.

Schema of :meth:`DiagnosisReport.to_json` (issue 6, section 2e)::

    {"location": {"junction": str, "bond": str, "windows": [[t0, t1], ...], "regime": str},
     "missing_physics": [{"kind": str, "attached_to": str, "parameters": {name: value},
                          "explanation": str, "judged_on": "held-out" | "training" | "open-loop",
                          "indistinguishable": [{"kind": str, "place": str,
                                                 "holdout_nrmse": {output: nrmse}, "z": float,
                                                 "difference": float, "n_params": int,
                                                 "unexcited": str, "structural": str}]}],
     "fit": {"holdout": [t0, t1], "nominal": {output: nrmse}, "improved": {output: nrmse},
             "window": [t0, t1], "start": str,
             "judge": "open-loop" | "segments", "judge_reason": str,
             "segments": {"count": int, "length": s, "samples": int, "estimation_samples": int},
             "open_loop": {"nominal": {output: nrmse}, "improved": {output: nrmse}}},
     "improved_model": path,
     "notes": [str]}

``missing_physics`` is ``[{"kind": "none", ...}]`` when nothing is missing;
``junction`` names the place the physics is attached to (a junction's
element name, or ``"input NAME"`` / ``"output NAME"`` for actuator and sensor
effects; ``""`` for none); ``bond`` is ``""`` when there is none;
``improved_model`` is ``null`` until :meth:`DiagnosisReport.save`;
``judged_on`` is ``"training"`` for an effect the held-out part cannot judge
(:mod:`diagnosis.training_judge`), ``"open-loop"`` for one the segment judge found within its
floor that predicts the held-out part open-loop to the noise (:mod:`diagnosis.open_loop_judge`),
else ``"held-out"``;
``indistinguishable`` lists, lowest held-out error first, the fits of other kinds in the effect's
round that the held-out part cannot tell apart from it (:mod:`diagnosis.alternatives`): their held-out
NRMSE, ``z`` of the lower error over the other's (below 3; ``null`` where it cannot be computed) and
``difference``, the largest difference of the two held-out predictions in noise standard deviations;
``unexcited`` (where present) says why a richer law was not fitted (the recording never excites it);
``structural`` (where present) says how a one-parameter scaling not fitted reads as the effect, rescaled
(:mod:`diagnosis.equivalent_readings`: its ``holdout_nrmse`` is empty, ``z`` null, and ``difference``
the largest difference of the swapped model's outputs from the answer's on the fit window);
``[]`` when there are none;
``fit.window`` is the part of the training samples the candidates were fitted on
and ``fit.start`` the state their simulations started from.  ``fit.judge`` says how the
held-out errors ``nominal`` and ``improved`` were measured (:mod:`diagnosis.segments`):
``"open-loop"`` (one simulation through training and held-out part) or ``"segments"`` (the
segment simulation error; ``segments`` gives their count, length in s and samples, and the
samples each one's state was estimated from); ``open_loop`` holds the open-loop held-out NRMSE
either way (``null`` where the run diverges).
``notes`` (present when there are any) are the notes on the recording: gaps in unbound columns,
constant columns, isolated spikes replaced (:mod:`diagnosis.outliers`);
``features`` (present when round 1 located a junction) holds the feature regression
at each located junction (:meth:`diagnosis.features.FeatureEvidence.to_json`):
``{"place", "unit", "selected": [kind], "selected_share", "kinds": [{"kind", "variant",
"detail", "share", "significant", "coefficients": {feature: value}}]}``, shares
dimensionless (validated share of the residual), coefficients in the junction's
effort (flow) unit per unit of the feature.
Times in s, NRMSE dimensionless.
"""
from __future__ import annotations

import json
import os
from dataclasses import dataclass, field

import numpy as np

__all__ = ["DiagnosisReport", "PlotData"]


@dataclass
class PlotData:
    """Arrays behind the report's plots (model units, times in s).

    Attributes
    ----------
    t : ndarray, shape (n,)
    measured, nominal, improved : dict str -> ndarray, shape (n,)
        Per output; ``improved`` is the nominal simulation when nothing was added.
    units : dict str -> str
    holdout_start : float
        First held-out time, s.
    regime_name : str or None
    regime_values : ndarray or None, shape (n_train,)
        The regime variable over the training part.
    regime_signal : ndarray or None, shape (n_train,)
        What was placed against it (the located correction or the residual).
    regime_label : str
    judge : str
        ``"open-loop"`` or ``"segments"`` (:mod:`diagnosis.segments`).
    segment_starts : list of float
        First time of each held-out segment, s (segment judge).
    nominal_segments, improved_segments : dict str -> ndarray, shape (n_held,), optional
        The segment simulations on the held-out part (NaN where not scored).
    """

    t: np.ndarray
    measured: dict
    nominal: dict
    improved: dict
    units: dict
    holdout_start: float
    regime_name: str | None = None
    regime_values: np.ndarray | None = None
    regime_signal: np.ndarray | None = None
    regime_label: str = ""
    judge: str = "open-loop"
    segment_starts: list = field(default_factory=list)
    nominal_segments: dict | None = None
    improved_segments: dict | None = None


def _finite(x):
    """JSON-safe float (NaN / inf become None)."""
    x = float(x)
    return x if np.isfinite(x) else None


@dataclass
class DiagnosisReport:
    """What :func:`diagnosis.diagnose.diagnose` found.

    Attributes
    ----------
    location : dict
        ``junction``, ``bond``, ``windows`` (list of [t0, t1], s), ``regime``.
    missing_physics : list of dict
        ``kind``, ``attached_to``, ``parameters`` (name -> SI value), ``explanation``,
        ``judged_on`` (``"held-out"``, or ``"training"`` when the held-out part never reaches
        the effect's regime: :mod:`diagnosis.training_judge`, or ``"open-loop"``:
        :mod:`diagnosis.open_loop_judge`), ``indistinguishable`` (the other
        readings the recording cannot tell apart: :mod:`diagnosis.alternatives`).
    fit : dict
        ``holdout`` [t0, t1] (s), ``nominal`` and ``improved`` held-out NRMSE per output.
    text : str
        The plain-language explanation.
    improved_graph : BondGraph
        The nominal graph with the winner added (and uncertain parameters refitted);
        the nominal graph itself when nothing was missing.
    improved_model : str or None
        Path of the improved graph's JSON once saved.
    scores : list of PlaceScore
        Graph location, best first.
    fits : list of CandidateFit
        Every candidate fitted.
    chosen : CandidateFit or None
    notes : list of str
        Recording notes (gaps, constant columns), warnings.
    timings : dict str -> float
        Seconds per step.
    plot_data : PlotData
    rounds : list of Round
        One :class:`~diagnosis.rounds.Round` per diagnosis round: ``chosen`` (CandidateFit or
        None), ``fits``, ``reference`` and ``improved`` held-out NRMSE per output, ``seconds``;
        from round 2 on also ``scores`` (the graph location of what was left); the last one the
        ``joint`` refit (:class:`~diagnosis.rounds.JointRefit`) when there were two effects or more.
    """

    location: dict
    missing_physics: list
    fit: dict
    text: str
    improved_graph: object
    improved_model: str | None = None
    scores: list = field(default_factory=list)
    fits: list = field(default_factory=list)
    chosen: object = None
    notes: list = field(default_factory=list)
    timings: dict = field(default_factory=dict)
    plot_data: PlotData | None = None
    rounds: list = field(default_factory=list)

    @property
    def kind(self) -> str:
        """The kind of the (first) missing physics, ``"none"`` when nothing is missing."""
        return self.missing_physics[0]["kind"] if self.missing_physics else "none"

    def to_json(self) -> dict:
        """The report in the issue's schema (see the module docstring); JSON-serialisable."""
        loc = self.location
        return {
            "location": {"junction": str(loc.get("junction", "")), "bond": str(loc.get("bond") or ""),
                         "windows": [[_finite(a), _finite(b)] for a, b in loc.get("windows", [])],
                         "regime": str(loc.get("regime", ""))},
            "missing_physics": [{"kind": m["kind"], "attached_to": m["attached_to"],
                                 "parameters": {k: _finite(v) for k, v in m["parameters"].items()},
                                 "explanation": m["explanation"],
                                 "judged_on": m.get("judged_on", "held-out"),
                                 **({"indistinguishable": list(m["indistinguishable"])}
                                    if "indistinguishable" in m else {})} for m in self.missing_physics],
            "fit": {"holdout": [_finite(v) for v in self.fit["holdout"]],
                    "nominal": {k: _finite(v) for k, v in self.fit["nominal"].items()},
                    "improved": {k: _finite(v) for k, v in self.fit["improved"].items()},
                    "substeps": int(self.fit.get("substeps", 1)),
                    **({"window": [_finite(v) for v in self.fit["window"]], "start": str(self.fit["start"])}
                       if "window" in self.fit else {}),
                    **({"judge": self.fit["judge"], "judge_reason": self.fit.get("judge_reason", "")}
                       if "judge" in self.fit else {}),
                    **({"segments": dict(self.fit["segments"])} if "segments" in self.fit else {}),
                    **({"open_loop": {k: {o: _finite(v) for o, v in d.items()}
                                      for k, d in self.fit["open_loop"].items()}}
                       if "open_loop" in self.fit else {})},
            "improved_model": self.improved_model,
            **({"notes": [str(n) for n in self.notes]} if self.notes else {}),
            **({"features": [ev.to_json() for ev in self.rounds[0].features]}
               if self.rounds and self.rounds[0].features else {}),
        }

    def improvement(self) -> dict:
        """Relative reduction of held-out NRMSE per output, ``1 - improved / nominal``."""
        nom, imp = self.fit["nominal"], self.fit["improved"]
        return {o: (1.0 - imp[o] / nom[o]) if nom[o] > 0 else 0.0 for o in nom}

    def save(self, directory, *, plots: bool = True) -> dict:
        """Write the report into `directory` (created if needed).

        Files: ``diagnosis.json`` (the schema), ``diagnosis.txt`` (the text),
        ``improved_model.json`` (the improved graph, :meth:`BondGraph.save`),
        and with `plots` ``residual_time.png``, ``residual_regime.png``,
        ``holdout_fit.png``.  Sets :attr:`improved_model`.

        Returns
        -------
        dict str -> str
            Paths by role (``json``, ``text``, ``model``, and the plot names).
        """
        os.makedirs(directory, exist_ok=True)
        paths = {"model": os.path.join(directory, "improved_model.json")}
        from bondgraph.io_json import save
        save(self.improved_graph, paths["model"])
        self.improved_model = paths["model"]
        paths["json"] = os.path.join(directory, "diagnosis.json")
        with open(paths["json"], "w") as fh:
            json.dump(self.to_json(), fh, indent=2)
        paths["text"] = os.path.join(directory, "diagnosis.txt")
        with open(paths["text"], "w") as fh:
            fh.write(self.text + "\n")
        if plots and self.plot_data is not None:
            from .report_plots import save_plots
            paths.update(save_plots(self, directory))
        return paths

    def __str__(self) -> str:
        return self.text
