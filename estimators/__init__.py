"""estimators: UKF, Kalman filter / steady-state observer, KPID, LQR/LQI design, PI.

Above ``fmus`` in the layer order of ``docs/architecture.md`` (imports ``bondgraph``, ``plants``, ``fmus``).

Unscented Kalman filter
-----------------------
UnscentedKalmanFilter   UKF on batched Python models or a bond-graph model (C step kernel)
UKFResult               estimates and covariances of ``batch_filter``
JulierSigmaPoints       the paper's sigma points (kappa; seed 000 uses 0)
MerweScaledSigmaPoints  scaled sigma points (alpha, beta, kappa)
SigmaPoints             base class of both
StateMap                linear map between filter and model coordinates

Linear Kalman filter, steady-state observers, LQR/LQI, PID/KPID, PI
--------------------------------------------------------------------
KalmanFilter              discrete linear Kalman filter (Joseph form), ``filter`` -> KalmanResult
discrete_kalman_gain      steady-state gain from the DARE -> ObserverGain
continuous_kalman_gain    Kalman-Bucy gain from the CARE (seed 004 eq. 9) -> ObserverGain
SteadyStateKalmanFilter   discrete filter with the DARE gain
ContinuousObserver        continuous observer (seed 004 eq. 8) run with exact ZOH steps
unobservable_modes        PBH test; also uncontrollable_modes, check_detectable, check_stabilizable, Mode
lqr, dlqr                 LQR -> LQRGain
lqi, dlqi                 LQR with single/double integral action (seed 004 eqs. 10-13) -> LQIGain
LQIController             runs an LQIGain: ``u = step(reference, x)``
augment_integral          the integral augmentation (and augment_integral_discrete)
PID, KPID                 discrete PID and Kalman-PID (seed 002 eq. 14); kpid_model, kpid_model_zoh
DiscretePI                the sensor-less PAM PI (seed 000, Sec. IV.C)
"""
from .sigma_points import JulierSigmaPoints, MerweScaledSigmaPoints, SigmaPoints
from .ukf import UKFResult, UnscentedKalmanFilter
from .ukf_model import StateMap

__all__: list[str] = [
    "UnscentedKalmanFilter", "UKFResult", "JulierSigmaPoints", "MerweScaledSigmaPoints",
    "SigmaPoints", "StateMap",
]

# -- linear estimators and controllers
from .kalman import KalmanFilter, KalmanResult  # noqa: E402
from .kpid import KPID, PID, kpid_model, kpid_model_zoh  # noqa: E402
from .lqi import LQIController, LQIGain, augment_integral, augment_integral_discrete, dlqi, lqi  # noqa: E402
from .lqr import LQRGain, dlqr, lqr  # noqa: E402
from .modes import Mode, check_detectable, check_stabilizable, uncontrollable_modes, unobservable_modes  # noqa: E402
from .observer import (ContinuousObserver, ObserverGain, SteadyStateKalmanFilter,  # noqa: E402
                       continuous_kalman_gain, discrete_kalman_gain)
from .pi import DiscretePI  # noqa: E402

__all__ += ["KalmanFilter", "KalmanResult", "discrete_kalman_gain", "continuous_kalman_gain", "ObserverGain",
            "SteadyStateKalmanFilter", "ContinuousObserver", "unobservable_modes", "uncontrollable_modes",
            "check_detectable", "check_stabilizable", "Mode", "lqr", "dlqr", "LQRGain", "lqi", "dlqi", "LQIGain",
            "augment_integral", "augment_integral_discrete", "LQIController", "PID", "KPID", "kpid_model",
            "kpid_model_zoh", "DiscretePI"]
