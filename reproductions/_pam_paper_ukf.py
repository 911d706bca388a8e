"""Seed 000's UKF set-up, shared by ``pam-ukf`` and ``pam-sensorless-pi``.

Section IV of [1]_ (line "The UKF parameters are determined as"), on the
paper's state :math:`x = (\\psi, \\dot\\psi, P_1, P_2)`:
:math:`P(0) = Q = \\mathrm{diag}(10^{-5}\\,\\mathrm{rad}^2, 10^{-4}\\,(\\mathrm{rad/s})^2,
10^6\\,\\mathrm{Pa}^2, 10^6\\,\\mathrm{Pa}^2)`, :math:`R = \\mathrm{diag}(10^8, 10^8)\\,\\mathrm{Pa}^2`,
Julier sigma points with :math:`\\kappa = 0`.  The locked joint keeps the
pressure block (``[2:, 2:]``).

References
----------
.. [1] T. Shin, T. Ibayashi, K. Kogiso, "Detailed dynamic model of antagonistic
   PAM system and its experimental validation: sensor-less angle and torque
   control with UKF", seed 000 (``docs/references.md``).
"""
from __future__ import annotations

import numpy as np

from estimators.ukf_model import StateMap

__all__ = ["PAPER_P0", "PAPER_Q", "PAPER_R", "KAPPA", "paper_state_map"]

PAPER_P0 = np.diag([1e-5, 1e-4, 1e6, 1e6])   # rad^2, (rad/s)^2, Pa^2, Pa^2
PAPER_Q = np.diag([1e-5, 1e-4, 1e6, 1e6])
PAPER_R = np.diag([1e8, 1e8])                 # Pa^2
KAPPA = 0.0                                   # Julier sigma-point parameter


def paper_state_map(state_names, J: float) -> StateMap:
    """The paper's :math:`(\\psi, \\dot\\psi, P_1, P_2)` over the pam model's states
    (``q_psi``, ``p_J = J psi'``, ``P_1``, ``P_2``); `J` in kg m^2."""
    return StateMap.scaled(state_names, {"psi": ("q_psi", 1.0), "dpsi": ("p_J", J),
                                         "P1": ("P_1", 1.0), "P2": ("P_2", 1.0)},
                           units=("rad", "rad/s", "Pa", "Pa"))
