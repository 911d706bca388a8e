"""The library mass-spring-damper as a hand-written truth for the diagnosis tests.

``m v' = F - b v - k x - extra(x, v)``, ``x' = v`` (m = 1 kg, b = 0.4 N s/m, k = 4 N/m, the
library's values), the force held over each sample, integrated by a classic RK4 written out here:
not bondgraph's integrator and not the catalogue's laws, so the diagnosis is checked against an
independent reference.
"""
import numpy as np


def msd_positions(t, force, extra=None, *, m=1.0, b=0.4, k=4.0, substeps=20):
    """Positions x(t) (m) from rest, `extra(x, v)` the concealed force (N) taken from the mass."""
    def rate(s, f):
        e = extra(s[0], s[1]) if extra is not None else 0.0
        return np.array([s[1], (f - b * s[1] - k * s[0] - e) / m])

    s, x = np.zeros(2), np.zeros(t.size)
    for i in range(t.size - 1):
        h = (t[i + 1] - t[i]) / substeps
        for _ in range(substeps):
            k1 = rate(s, force[i])
            k2 = rate(s + h / 2 * k1, force[i])
            k3 = rate(s + h / 2 * k2, force[i])
            k4 = rate(s + h * k3, force[i])
            s = s + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        x[i + 1] = s[0]
    return x
