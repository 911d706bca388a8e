"""Building blocks of scenario ``pam-sensorless-pi``: the PI and sensor blocks, the loop.

Fig. 13 of [1]_: the rig (FMU) is measured by two pressure sensors; a UKF on
the nominal model estimates the angle (a) or the torque (b) from the two
pressures and the two valve commands; the discrete PI of Section IV.C acts on
the error between the reference and the estimate.  The true angle / torque
(the rig's outputs) is only logged, to evaluate the tracking.

Signals (``component.port``, unit)::

    reference.y (deg | N m) ---------------------------> pi.r
    ukf.psi_hat (deg) | ukf.tau_hat (N m) -------------> pi.y_m
    pi.u1, pi.u2 (V) ----------> rig.u1, rig.u2 and ukf.u1, ukf.u2
    rig.P1, rig.P2 (Pa) -------> sensors.P1_true, sensors.P2_true
    sensors.P1, sensors.P2 (Pa) ----------------------> ukf.P1, ukf.P2

References
----------
.. [1] T. Shin, T. Ibayashi, K. Kogiso, "Detailed dynamic model of antagonistic
   PAM system and its experimental validation: sensor-less angle and torque
   control with UKF", seed 000 (``docs/references.md``).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

import plants.library as library
from plants.blockdiagram import pam as pam_bd
from .errors import CosimError
from bondgraph.numerics.evaluate import compile_model
from estimators import DiscretePI, JulierSigmaPoints

from cosim.blocks import Table
from cosim.component import Port, PythonBlock
from cosim.estimator_blocks import UKFBlock
from cosim.fmu_component import FMUComponent
from cosim.master import CoSimulation
from ._pam_paper_ukf import KAPPA, PAPER_P0, PAPER_Q, PAPER_R, paper_state_map
from ._pam_rig import export_rig, rig_start_values

__all__ = ["DiscretePIBlock", "PressureSensors", "build_loop", "BETA", "SAMPLE", "NOISE_PA",
           "UKF_P0", "UKF_Q", "UKF_R"]

BETA = 5.5          # V, bias of both valves (Section IV.C of [1])
SAMPLE = 1e-3       # s, sampling period T_stp = communication step
#: Pressure-sensor noise, Pa (standard deviation): E8F2-B10C, 1 MPa full scale, +-1 % FS;
#: it matches the paper's R = diag(1e8, 1e8) Pa^2.
NOISE_PA = 1e4
# Section IV of [1]: P(0), Q, R of the UKF, x = (psi, dpsi, P1, P2)
UKF_P0, UKF_Q, UKF_R = PAPER_P0, PAPER_Q, PAPER_R


class DiscretePIBlock(PythonBlock):
    """:class:`~estimators.DiscretePI` as a component: inputs ``r``, ``y_m``; outputs ``u1``, ``u2`` (V).

    ``u(k) = C x(k) + D e(k) + beta`` with ``e(k) = r(k) - y_m(k)`` feeds
    through; the state update ``x(k+1) = x(k) + e(k)`` is committed in
    :meth:`advance` (so :meth:`output` may be called again at the same time).

    Parameters
    ----------
    name : str
    controller : DiscretePI
    unit : str
        Unit of the reference and the measurement (``"deg"``, ``"rad"``, ``"N m"``).
    """

    def __init__(self, name: str, controller: DiscretePI, unit: str):
        if not isinstance(controller, DiscretePI):
            raise CosimError(f"block {name!r}: controller must be a DiscretePI; found {controller!r}")
        self.controller = controller
        beta = controller.beta
        super().__init__(name, inputs=[Port("r", unit, "reference"), Port("y_m", unit, "estimate")],
                         outputs=[Port("u1", "V", "valve 1 command", float(beta[0])),
                                  Port("u2", "V", "valve 2 command", float(beta[1]))])
        self._x_next = 0.0

    def start(self, t0: float) -> None:
        self.controller.reset()

    def output(self, t: float) -> None:
        pi = self.controller
        x_now = pi.x
        self.y[:] = pi.step(self.u[0], self.u[1])   # also adds e(k) to pi.x ...
        self._x_next, pi.x = pi.x, x_now           # ... which advance() commits

    def advance(self, t: float, dt: float) -> None:
        self.controller.x = self._x_next


class PressureSensors(PythonBlock):
    """Two pressure sensors: ``P_i = P_i_true + v_i``, white Gaussian ``v_i`` drawn per step.

    Parameters
    ----------
    name : str
    sigma : float, Pa
        Noise standard deviation (>= 0).
    rng : numpy.random.Generator
        Seeded by the caller; one pair of samples per communication point.
    """

    def __init__(self, name: str, sigma: float, rng: np.random.Generator):
        if not (np.isfinite(sigma) and sigma >= 0):
            raise CosimError(f"block {name!r}: sigma must be a finite value >= 0 Pa; found {sigma!r}")
        self.sigma, self.rng = float(sigma), rng
        super().__init__(name, inputs=[Port("P1_true", "Pa"), Port("P2_true", "Pa")],
                         outputs=[Port("P1", "Pa", "measured P1"), Port("P2", "Pa", "measured P2")],
                         feedthrough=[("P1_true", "P1"), ("P2_true", "P2")])
        self._v = np.zeros(2)

    def start(self, t0: float) -> None:
        self._v = self.rng.normal(0.0, self.sigma, 2)

    def output(self, t: float) -> None:
        self.y[:] = self.u + self._v

    def advance(self, t: float, dt: float) -> None:
        self._v = self.rng.normal(0.0, self.sigma, 2)


def _ukf_block(locked: bool) -> UKFBlock:
    """The paper's UKF on the NOMINAL model, started at the nominal rest state under beta."""
    name = "pam-locked" if locked else "pam"
    model = compile_model(library.build(name).equations())
    rest = pam_bd.equilibrium([BETA, BETA], variant="locked" if locked else "full")  # rad, rad/s, Pa, Pa
    points = JulierSigmaPoints(2 if locked else 4, kappa=KAPPA)
    if locked:   # psi = dpsi = 0: the filter keeps the pressure block of P(0), Q
        return UKFBlock.from_model("ukf", model, dt=SAMPLE, outputs=("P1", "P2"), x0=rest[2:],
                                   P0=UKF_P0[2:, 2:], Q=UKF_Q[2:, 2:], R=UKF_R, points=points,
                                   estimates=("tau",))
    J = model.default_params[model.param_index["J"]]
    smap = paper_state_map(model.state_names, J)
    return UKFBlock.from_model("ukf", model, dt=SAMPLE, outputs=("P1", "P2"), x0=rest, P0=UKF_P0,
                               Q=UKF_Q, R=UKF_R, points=points, state_map=smap,
                               estimates=("psi", "tau"))


def build_loop(loop: str, times, values, fmu_dir, *, reading: str = "deg", pi_reading: str = "gain",
               seed: int = 0, noise_pa: float = NOISE_PA) -> CoSimulation:
    """The closed loop of Fig. 13 of [1]_ ((a) ``"angle"``, (b) ``"torque"``), ready to run.

    Parameters
    ----------
    loop : {"angle", "torque"}
        ``"torque"`` locks the joint at psi = 0 (``pam-locked``), as the
        paper's torque experiments do (Section IV-A 2: "the joint angle was
        fixed at 0 deg").
    times, values : array_like
        Reference steps: ``values[i]`` (deg, or N m) from ``times[i]`` (s) on.
    fmu_dir : path-like
        Where the rig FMU is written.
    reading : {"deg", "rad"}
        Unit of the angle error ``e`` fed to the PI (``"deg"``: the model's
        output psi, eq. (11b); ``"rad"``: the state); ignored for the torque.
    pi_reading : {"gain", "printed"}
        :math:`C = \\pm T_I T_{stp}` or :math:`\\pm T_I / T_{stp}` as printed
        (:class:`~estimators.DiscretePI`).
    seed : int
        Seed of the pressure noise.
    noise_pa : float, Pa
        Pressure-sensor noise standard deviation.

    Returns
    -------
    CoSimulation
    """
    if loop not in ("angle", "torque"):
        raise CosimError(f"loop must be 'angle' or 'torque'; found {loop!r}")
    if reading not in ("deg", "rad"):
        raise CosimError(f"reading must be 'deg' or 'rad'; found {reading!r}")
    locked = loop == "torque"
    fmu = export_rig(Path(fmu_dir) / f"rig_{loop}.fmu", locked=locked)
    rig = FMUComponent(fmu, "rig", start_values=rig_start_values((BETA, BETA), locked=locked))
    unit, values = ("N m", np.asarray(values, float)) if locked else (
        (reading, np.asarray(values, float) * (1.0 if reading == "deg" else np.pi / 180)))
    estimate = {"N m": "ukf.tau_hat", "deg": "ukf.psi_hat", "rad": "ukf.x_psi"}[unit]
    reference = Table("reference", times, values, unit=unit, interpolation="hold")
    controller = DiscretePI.from_paper(loop, Tstp=SAMPLE, beta=BETA, reading=pi_reading)
    pi = DiscretePIBlock("pi", controller, unit)
    sensors = PressureSensors("sensors", noise_pa, np.random.default_rng(seed))
    connections = [("reference.y", "pi.r"), (estimate, "pi.y_m"),
                   ("pi.u1", "rig.u1"), ("pi.u2", "rig.u2"), ("pi.u1", "ukf.u1"), ("pi.u2", "ukf.u2"),
                   ("rig.P1", "sensors.P1_true"), ("rig.P2", "sensors.P2_true"),
                   ("sensors.P1", "ukf.P1"), ("sensors.P2", "ukf.P2")]
    return CoSimulation([reference, pi, _ukf_block(locked), sensors, rig], connections, step=SAMPLE)
