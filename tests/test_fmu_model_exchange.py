"""Model Exchange as the FMI standard wants it: a point outside the model's domain is a
Discard the importer can recover from (FMI 2.0 sec. 2.1.3, FMI 3.0 sec. 2.2.3), driven
through fmpy's own FMU2Model / FMU3Model and its CVode integration."""
from __future__ import annotations

import math

import numpy as np
import pytest
from fmpy import simulate_fmu
from fmpy.fmi1 import FMICallException

from fmu_helpers import Model

VERSIONS = (2, 3)
DISCARD = 2   # fmi2Discard == fmi3Discard


@pytest.fixture(scope="module")
def vented(exported_fmu):
    return {v: exported_fmu("pam-frictionless", v) for v in VERSIONS}


@pytest.mark.parametrize("version", VERSIONS)
def test_a_state_outside_the_domain_is_a_recoverable_discard(vented, version):
    m = Model(vented[version])
    try:
        m.start()
        x0, dx0 = m.x(), m.dx()
        names = m.state_names
        bad = x0.copy()
        bad[names.index("q_psi")] = 0.7   # V_2 < 0 there (eq. (3), Table II; test_fmu_guards)
        m.set_x(bad)
        with pytest.raises(FMICallException) as info:
            m.dx()
        assert info.value.status == DISCARD
        assert "V_2 = -6.09" in m.messages[-1] and "left its physical domain" in m.messages[-1]
        with pytest.raises(FMICallException) as info:
            m.completed()
        assert info.value.status == DISCARD and "CompletedIntegratorStep" in m.messages[-1]
        m.set_x(x0)                       # recoverable: other states are taken
        assert np.array_equal(m.dx(), dx0)
        assert m.completed()[1] is False or m.completed()[1] == 0
        bad[names.index("q_psi")] = math.nan
        m.set_x(bad)
        with pytest.raises(FMICallException) as info:
            m.dx()
        assert info.value.status == DISCARD and "q_psi" in m.messages[-1]
    finally:
        m.close()


@pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")   # fmpy's callbacks
@pytest.mark.parametrize("version", VERSIONS)
def test_cvode_stops_at_the_vanishing_chamber_with_discards_logged(vented, version):
    # The vented joint swings until muscle 2's volume vanishes (test_fmu_guards: CS and
    # bondgraph.numerics.simulate stop there within 20-40 ms); fmpy's CVode cannot pass that point.
    messages, times = [], []

    def logger(*args):
        messages.append(args[-1].decode())

    def step_finished(t, recorder):
        times.append(t)
        return True

    with pytest.raises((RuntimeError, FMICallException)):
        simulate_fmu(str(vented[version]), stop_time=0.1, output_interval=1e-3,
                     fmi_type="ModelExchange", relative_tolerance=1e-8, logger=logger,
                     step_finished=step_finished)
    assert 0.02 <= times[-1] <= 0.04
    discards = [msg for msg in messages if "left its physical domain" in msg]
    assert discards and all("V_2" in msg or "P_2_abs" in msg for msg in discards)
