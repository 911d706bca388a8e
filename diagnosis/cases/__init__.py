"""Recordings with concealed effects: the diagnosis test set and its generator.

Each case drives a TRUTH model -- an unmodified built-in library model (the
NOMINAL model a diagnosis is given) plus one concealed effect written by hand
in :mod:`diagnosis.cases.truth`, independently of the diagnosis catalogue --
with a seeded, realistic excitation, and records its inputs and outputs
through simulated sensors (Gaussian noise, then quantisation to the sensor's
resolution) into a small CSV file whose columns carry their units in their
names (``x_mm``, ``P1_kPa``, ``w_m_rpm``).  Null cases have no effect.

``python -m diagnosis.cases OUTDIR [CASE ...]`` regenerates the CSV files and
the manifest ``cases.json``; the committed copies live in
``tests/data/diagnosis/``.  Generation is deterministic: each case owns a seed
(``numpy.random.default_rng(seed)`` draws the excitation, then the noise of
each output in order), and the model is driven by exactly the command values
written to the file, as zero-order-hold tables.

Manifest fields (one entry per case)
------------------------------------
``name``, ``file``, ``model`` (nominal, ``plants.library`` name),
``description`` (one line), ``kind`` (issue 6 vocabulary, or ``"none"``),
``place`` (``{"kind": "junction"|"input"|"output", "name": ...}`` or null),
``equivalent_places`` (places no recording can tell from ``place``, e.g. a
junction rigidly geared to it) and ``equivalence`` (why),
``parameters`` (true values with units), ``affected_output``, ``time``
(time column), ``inputs`` / ``outputs`` (``NAME=COLUMN:UNIT`` bindings),
``model_units``, ``seed``, ``sample_rate_Hz``, ``duration_s``,
``excitation`` (profile and amplitudes), ``noise`` (per output: column, unit,
``sigma``, ``quantum``, ``effective_sigma`` = sqrt(sigma^2 + quantum^2/12)),
``min_effect_to_noise`` (documented floor) and ``effect_to_noise`` (measured:
RMS of truth minus nominal, noise-free, of the affected output over its
effective sigma) and ``holdout_effect_to_noise`` (the same over the last 30 %
of the span, the diagnosis' default hold-out: a 50 % lower held-out NRMSE
needs it above sqrt(3)).

What makes a case hard
----------------------
* Places no data can separate: a 1-junction rigidly geared through a TF is
  the same degree of freedom (``dcmotor_stribeck``: w_load ~ w_motor;
  ``exo_viscous``: w_m ~ w_g), so the manifest lists them as equivalent.
* Actuator effects on a source (``dcmotor_saturation``, ``exo_delay``,
  ``pam_valve_lag``) look like an extra effort at the source's junction;
  only the input place explains them with a law of the command.
* Regime coverage: Stribeck needs low speeds of both signs (a stepped ramp),
  a hardening spring needs several amplitudes (random force levels), a leak
  and a level offset in slow tanks separate only through the level history.
* The PAM plant is non-smooth (held Kikuuwe friction, fixed-step RK4) and
  already holds pressure-dependent friction; extra seal friction partly hides
  in its stick band, and a valve lag shows weakly in the pressures (the
  orifices are slower than the lag) - hence 120 ms and the +-4.5 V excitation.
* Null cases must come out ``none`` although the residual is never exactly
  white (quantisation, the sensor resolution close to the noise).

Public names
------------
``CASES``, ``Case``, ``Signal``, ``case`` (definitions); ``record``,
``simulate_case``, ``write_all``, ``MANIFEST`` (generator); the effect classes
live in :mod:`diagnosis.cases.truth`.

Examples
--------
>>> from diagnosis.cases import CASES
>>> len({c.kind for c in CASES if c.kind != "none"}) >= 8
True
"""
from .definitions import CASES, Case, Signal, case
from .generate import MANIFEST, record, simulate_case, write_all

__all__ = ["CASES", "Case", "Signal", "case", "MANIFEST", "record", "simulate_case", "write_all"]
