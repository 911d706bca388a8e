"""diagnosis: when simulation and recordings differ, locate the mismatch, name the missing physics.

Above ``reproductions`` in the layer order of ``docs/architecture.md`` (may import bondgraph, plants,
fmus, estimators, cosim, reproductions).

Pipeline (:func:`diagnosis.diagnose.diagnose`)
----------------------------------------------
1. ``recording``/``units``: read a CSV (time column + named signals), bind
   columns to model inputs/outputs with unit conversion -> :class:`Experiment`
   (all arrays in the model's units, time in s); split off a held-out tail.
2. ``residuals``: simulate the nominal model on the recorded inputs (inputs as
   zero-order-hold tables, delayed inputs shifted on their samples); residual = measured -
   simulated per output; measurement-noise level; NRMSE; the RK4 sub-steps the recording needs
   (``settle_substeps``).
3. ``locate``: where the residual is significant in time (windows), in which
   operating regime (sign of a velocity, pressure level, amplitude ...), and
   ``graph_location``: at which junction an extra effort (1-junction) or flow
   (0-junction), or at which input/output a correction, explains it, ranked by
   the share of residual explained.
4. ``catalogue``: candidate elements by physical name (``KINDS``; each kind one
   class in the registry :mod:`diagnosis.kinds`), each
   attached to a :class:`Place` as a proper bond-graph element (or an input /
   output transformation for sensor and actuator effects), with parameters,
   guesses and bounds; ``fit``: simulation-error least squares on the training
   part, NRMSE on the held-out part, parsimony, ``none`` when nothing explains
   a significant share; ``alternatives``: the fits of other kinds the held-out
   part cannot tell apart from the answer.
5. ``report``: :class:`DiagnosisReport` - JSON (issue schema), plain-language
   explanation, plots, improved graph as JSON.

Shared definitions
------------------
* NRMSE of an output: ``rms(y_meas - y_sim) / std(y_meas)`` over the samples
  compared (:func:`diagnosis.residuals.nrmse`).
* A :class:`~diagnosis.catalogue.Place` is ``(kind, name)`` with kind in
  ``{"junction", "input", "output"}``; junction places carry an extra effort at
  a 1-junction and an extra flow at a 0-junction.
"""
__all__: list[str] = []
