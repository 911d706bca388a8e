"""The PAM bond graph against the independently written state-space model (11a).

Both implement the same fixed-step scheme (pam-conventions.md), so on a
Fig. 8-like profile they must agree to rounding: 1e-6 relative to each
signal's range (the largest difference seen is about 1e-13 of it).
"""
import numpy as np
import pytest

from plants.blockdiagram.pam_compare import SIGNALS, compare_fig8


@pytest.mark.parametrize("variant", ["full", "frictionless", "locked"])
def test_bond_graph_equals_state_space_model(variant, tmp_path):
    run = compare_fig8(variant=variant, duration=6.0, segment=1.5)
    for name in SIGNALS:
        span = np.ptp(run.block_diagram[name]) or 1.0
        assert run.max_abs_error[name] <= 1e-6 * span + 1e-12, (name, run.max_abs_error[name], span)
    assert np.ptp(run.block_diagram["P1"]) > 5e4   # the profile really moves the pressures
    if variant == "locked":
        assert np.all(run.bond_graph["psi"] == 0)
    else:
        assert np.ptp(run.block_diagram["psi"]) > 1.0
    path = run.plot(tmp_path / "pam.png")
    assert path.stat().st_size > 10000
