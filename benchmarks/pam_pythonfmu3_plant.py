"""The ``pam`` plant as a pythonfmu3 (FMI 3.0 Co-Simulation) slave, for ``benchmarks/cosim.py``.

Built into an ``.fmu`` by :func:`cosim_peers.build_pythonfmu3_plant` (pythonfmu3's
``FmuBuilder``); not part of the package, and pythonfmu3 is a benchmark-only
dependency (``pip install pythonfmu3``).

The plant is the numpy state-space model :mod:`plants.blockdiagram.pam`, stepped
with its own fixed-step scheme: each 1 ms sample holds ``u1``, ``u2`` and is
integrated by 4 classic RK4 sub-steps of 0.25 ms, the Kikuuwe friction torque being
evaluated at the start of each sub-step and held over it.  ``do_step`` calls
:func:`plants.blockdiagram.pam.simulate` for the step's whole number of samples,
starting from the state the previous step ended in, so the FMU reproduces a single
``pam.simulate`` run over the same input sequence exactly (that function runs
the scheme on Python floats; the same scheme written with the array functions
``pam.derivatives`` / ``pam.kikuuwe_friction`` is about 10x slower per step).

Variables (value references in registration order):

========  ==========  ===========  =======================================
name      causality   unit         meaning
========  ==========  ===========  =======================================
time      independent s
u1, u2    input       V            valve voltages (clipped to [0, 10] V)
psi       output      deg          joint angle
P1, P2    output      Pa           muscle pressures (absolute)
tau       output      N.m          joint torque of the muscles, eq. (9)
psi0      parameter   rad          initial angle
dpsi0     parameter   rad/s        initial angular velocity
P1_0      parameter   Pa           initial pressure of muscle 1
P2_0      parameter   Pa           initial pressure of muscle 2
========  ==========  ===========  =======================================

The initial state defaults to ``pam.simulate``'s default ``(0, 0, P_out, P_out)``;
set the ``*0`` parameters before ``exitInitializationMode``.  A step must be a whole
number (>= 1) of 1 ms samples (otherwise ``doStep`` returns an error status).

Runtime requirement: the FMU's shared library runs this file in the importing
process's own Python interpreter.  It imports ``bondgraph`` from that interpreter's
``sys.path``.  The FMU does not bundle ``bondgraph``, so the repository root must be
importable.  ``cosim_peers`` puts it on the path.
"""
from __future__ import annotations

import math

import numpy as _np
from pythonfmu3 import (
    Float64,
    Fmi3Causality,
    Fmi3Slave,
    Fmi3Status,
    Fmi3StepResult,
    Fmi3Variability,
    Unit,
)

try:
    from plants.blockdiagram import pam as _pam
except ImportError as exc:  # pragma: no cover - depends on the importer's sys.path
    raise ImportError(
        "the pam pythonfmu3 FMU needs the bondcosim repository (package 'bondgraph') on the "
        "importing Python's sys.path") from exc


# SI definitions of every unit used (fmpy rejects a modelDescription whose units are undeclared)
_UNITS = [Unit("s", s=1), Unit("V", kg=1, m=2, s=-3, A=-1), Unit("rad", rad=1),
          Unit("deg", rad=1, factor=math.pi / 180.0), Unit("rad/s", rad=1, s=-1),
          Unit("Pa", kg=1, m=-1, s=-2), Unit("N.m", kg=1, m=2, s=-2)]


class PamPlant(Fmi3Slave):
    """Antagonistic pneumatic-muscle joint (``pam``), inputs u1, u2 (V)."""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.author = "bondcosim benchmarks"
        self.description = ("Antagonistic PAM joint (numpy state-space model of plants.blockdiagram.pam); "
                            "1 ms samples of 4 RK4 sub-steps with held Kikuuwe friction")
        p = _pam.PARAMS
        self.time = 0.0
        self.u1 = 0.0
        self.u2 = 0.0
        self.psi0 = 0.0
        self.dpsi0 = 0.0
        self.P1_0 = p["P_out"]
        self.P2_0 = p["P_out"]
        self._x = _np.array([self.psi0, self.dpsi0, self.P1_0, self.P2_0])
        self._u = _np.zeros((1, 2))
        self._set_outputs(self._x)

        self.register_units(_UNITS)
        self.register_variable(Float64("time", causality=Fmi3Causality.independent,
                                       variability=Fmi3Variability.continuous, unit="s"))
        for name in ("u1", "u2"):
            self.register_variable(Float64(name, causality=Fmi3Causality.input, start=0.0, unit="V",
                                           description=f"valve voltage {name}, clipped to [0, 10] V"))
        for name, unit, text in (("psi", "deg", "joint angle"),
                                 ("P1", "Pa", "pressure of muscle 1 (absolute)"),
                                 ("P2", "Pa", "pressure of muscle 2 (absolute)"),
                                 ("tau", "N.m", "joint torque of the muscles, r cos(psi) (F1 - F2)")):
            self.register_variable(Float64(name, causality=Fmi3Causality.output, unit=unit, description=text))
        for name, unit, text in (("psi0", "rad", "initial joint angle"),
                                 ("dpsi0", "rad/s", "initial angular velocity"),
                                 ("P1_0", "Pa", "initial pressure of muscle 1 (absolute)"),
                                 ("P2_0", "Pa", "initial pressure of muscle 2 (absolute)")):
            self.register_variable(Float64(name, causality=Fmi3Causality.parameter,
                                           variability=Fmi3Variability.fixed, start=getattr(self, name),
                                           unit=unit, description=text))

    def _set_outputs(self, x) -> None:
        self.psi = float(_np.degrees(x[0]))
        self.P1 = float(x[2])
        self.P2 = float(x[3])
        self.tau = float(_pam.joint_torque(x))

    def exit_initialization_mode(self):
        self._x = _np.array([self.psi0, self.dpsi0, self.P1_0, self.P2_0], dtype=float)
        self._set_outputs(self._x)

    def do_step(self, current_time, step_size):
        n = round(step_size / _pam.SAMPLE_TIME)
        if n < 1 or abs(n * _pam.SAMPLE_TIME - step_size) > 1e-9:
            self.log(f"step size {step_size!r} s is not a whole number (>= 1) of "
                     f"{_pam.SAMPLE_TIME} s samples", Fmi3Status.error)
            return Fmi3StepResult(status=Fmi3Status.error)
        u = self._u
        if len(u) != n:
            u = self._u = _np.empty((n, 2))
        u[:, 0] = self.u1
        u[:, 1] = self.u2
        out = _pam.simulate(u, n * _pam.SAMPLE_TIME, x0=self._x)
        self._x = out["x"][-1]
        self.psi = float(out["psi_deg"][-1])
        self.P1 = float(out["P1"][-1])
        self.P2 = float(out["P2"][-1])
        self.tau = float(out["tau"][-1])
        self.time = current_time + step_size
        return True
