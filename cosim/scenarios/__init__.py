"""Closed-loop scenarios around the seed plants, each plant an exported FMU in the master.

``pam_pi``
    The PAM joint under a PI angle loop (:func:`cosim.scenarios.pam_pi.run`).
"""
