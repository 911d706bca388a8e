"""The library mass-spring-damper as a hand-written truth for the diagnosis tests, and the RK4 it runs on.

``m v' = F - b v - k x - extra(x, v)``, ``x' = v`` (m = 1 kg, b = 0.4 N s/m, k = 4 N/m, the
library's values), the force held over each sample, integrated by a classic RK4 written out here:
not bondgraph's integrator and not the catalogue's laws, so the diagnosis is checked against an
independent reference.
"""
import numpy as np


def rk4_states(rate, t, force, *, substeps, x0=(0.0, 0.0)):
    """States of x' = rate(x, F) (as many as `x0` has) at the sample times, from `x0` (default two at
    rest), F held over each interval; classic RK4 written out here, not bondgraph's integrator."""
    state = np.array(x0, dtype=float)
    out = np.zeros((t.size, state.size))
    out[0] = state
    for i in range(t.size - 1):
        h = (t[i + 1] - t[i]) / substeps
        for _ in range(substeps):
            k1 = rate(state, force[i])
            k2 = rate(state + h / 2 * k1, force[i])
            k3 = rate(state + h / 2 * k2, force[i])
            k4 = rate(state + h * k3, force[i])
            state = state + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        out[i + 1] = state
    return out


def msd_positions(t, force, extra=None, *, m=1.0, b=0.4, k=4.0, substeps=20, x0=(0.0, 0.0)):
    """Positions x(t) (m) from `x0` (position m, velocity m/s; default rest), `extra(x, v)` the
    concealed force (N) taken from the mass."""
    def rate(s, f):
        e = extra(s[0], s[1]) if extra is not None else 0.0
        return np.array([s[1], (f - b * s[1] - k * s[0] - e) / m])

    return rk4_states(rate, t, force, substeps=substeps, x0=x0)[:, 0]
