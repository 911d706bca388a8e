"""Scenarios of cosim.scenarios: seed plants exported as FMUs, closed loops in the master."""
import numpy as np
import pytest

from cosim.scenarios import pam_pi


def test_pam_pi_scenario_tracks_the_setpoints(tmp_path):
    res = pam_pi.simulate(tmp_path)
    assert res.info["n_steps"] == 13000
    # the loop pulls the joint from its 10 deg rest angle to each setpoint (deg)
    for t_end, target in ((4.0, 10.0), (7.0, -10.0), (13.0, 0.0)):
        k = int(round(t_end / 1e-3))
        assert abs(res["plant.psi"][k] - target) < 2.0, (t_end, res["plant.psi"][k])
    assert res["plant.psi"][0] == pytest.approx(10.3, abs=0.5)
    u1, u2 = res["plant.u1"], res["plant.u2"]
    assert u1.min() >= 0.0 and u1.max() <= 10.0 and np.allclose(u1 + u2, 10.0)   # valve range, split
    assert (tmp_path / "cosim_pam_pi.csv").exists() and (tmp_path / "cosim_pam_pi.png").exists()


def test_cosim_cli_runs_a_scenario_and_names_unknown_ones(tmp_path, capsys):
    import json

    from bondcosim.cli import main
    assert main(["cosim", "pam-pi", "--json", "--plot", str(tmp_path)]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["steps"] == 13000 and data["settled_error_deg"] < 5.0
    assert (tmp_path / "cosim_pam_pi.png").exists()
    assert main(["cosim", "no-such"]) == 1
    err = capsys.readouterr().err
    assert "no-such" in err and "pam-pi" in err
