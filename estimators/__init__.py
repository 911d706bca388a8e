"""estimators: UKF, Kalman filter / steady-state observer, KPID, LQR/LQI design, PI.

Layer 3 of the design (imports ``bondgraph`` and ``fmus``).  Arrives with the estimators issue.
"""
__all__: list[str] = []
