"""An actuator limit on an input of a few held levels (a PRBS), as rigs are often excited.

Truth (hand-written RK4, tests/msd_truth.py): the library mass-spring-damper whose force
actuator delivers at most 1.2 N; the recorded command switches between -1 N and +2 N.  Every
quantile of such an input is one of its two levels, where a limit clips nothing: the fit must
also start inside the recorded span to see the limit at all.
"""
import numpy as np
import pytest

from diagnosis.diagnose import diagnose
from msd_truth import msd_positions

FS, SPAN, SIGMA, LIMIT = 50.0, 30.0, 5e-3, 1.2        # Hz, s, m, N


def _prbs(t, rng, low=-1.0, high=2.0):
    """Two levels, each held a random 1-3 s."""
    out, level, until = np.empty(t.size), high, 0.0
    for i, ti in enumerate(t):
        if ti >= until:
            level = low if level == high else high
            until = ti + rng.uniform(1.0, 3.0)
        out[i] = level
    return out


def test_a_limit_between_the_levels_of_a_prbs_input_is_found(tmp_path):
    rng = np.random.default_rng(3)
    t = np.arange(0.0, SPAN, 1.0 / FS)
    command = _prbs(t, rng)
    x = msd_positions(t, np.minimum(command, LIMIT)) + rng.normal(0.0, SIGMA, t.size)
    path = tmp_path / "msd_prbs.csv"
    path.write_text("t,F,x\n" + "\n".join(f"{a:.6f},{f:.9g},{p:.6g}" for a, f, p in zip(t, command, x)) + "\n")
    report = diagnose("mass-spring-damper", str(path), inputs=["F=F:N"], outputs=["x=x:m"], max_effects=1)
    data = report.to_json()
    (effect,) = data["missing_physics"]
    assert (effect["kind"], effect["attached_to"]) == ("saturation", "input F")
    assert effect["parameters"]["u_max_F"] == pytest.approx(LIMIT, abs=0.02)
    assert effect["parameters"]["u_min_F"] <= -1.0          # the low level is never clipped
    nominal, improved = data["fit"]["nominal"]["x"], data["fit"]["improved"]["x"]
    assert improved < 0.2 * nominal


@pytest.mark.parametrize("level", [0.0, 3.33e5])
def test_a_constant_input_still_gets_a_valid_saturation_candidate(level):
    """An input held constant (a load torque recorded as 0, a supply pressure held at 333 kPa) has
    no span to start a limit inside: the candidate is offered with its plain starts (no start
    outside its bounds).  At 333 kPa a span floored at 1e-12 vanished in floating point, and the
    candidate's bounds collapsed onto the level: the whole diagnosis stopped (seed 2929, case 029)."""
    from diagnosis.catalogue import candidates
    from diagnosis.place import Place
    from diagnosis.recording import Experiment
    import plants

    t = np.arange(0.0, 2.0, 0.02)
    exp = Experiment(t, {"F": np.full(t.size, level)}, {"x": np.zeros(t.size)}, {"F": "N", "x": "m"}, "constant")
    (sat,) = [c for c in candidates(plants.load("mass-spring-damper"), Place("input", "F"), experiment=exp)
              if c.kind == "saturation"]
    assert all(p.lower <= s[p.name] <= p.upper for s in sat.starts for p in sat.params if p.name in s)
    assert all(p.lower < p.guess < p.upper for p in sat.params)
