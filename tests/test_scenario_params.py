"""Scenario parameter overrides (``reproductions.run(params=, seed=, fmu_dir=)``), used by sweeps."""
import pytest

from bondgraph.errors import ParameterError, UnknownNameError
from plants.library.pam import PARAMETERS as PAM
import reproductions as scenarios
from reproductions._pam_rig import RIG_PERTURBATION, rig_params


def test_pam_ukf_parameters_default_to_the_rig():
    table = scenarios.parameters("pam-ukf")
    # the rig of reproductions/_pam_rig.py: Table II times RIG_PERTURBATION
    assert table["A1"].value == pytest.approx(PAM["A1"].value * RIG_PERTURBATION["A1"], rel=1e-12)
    assert table["A1"].unit == "m^2" and table["segment_s"].unit == "s" and table["sigma_p"].unit == "Pa"
    assert table["J"].value == PAM["J"].value
    assert rig_params({"A1": 6e-8})["A1"] == 6e-8 and rig_params({"A1": 6e-8})["A2"] == rig_params()["A2"]


def test_reused_fmus_and_explicit_defaults_give_the_scenario_numbers(tmp_path):
    plain = scenarios.run("pam-ukf", quick=True)
    assert set(scenarios.export_fmus("pam-ukf", tmp_path)) == {"free", "locked"}
    defaults = {"A1": scenarios.parameters("pam-ukf")["A1"].value}
    reused = scenarios.run("pam-ukf", quick=True, fmu_dir=tmp_path, params=defaults, seed=5)
    assert reused["ukf"] == plain["ukf"] and reused["model_only"] == plain["model_only"]


def test_a_varied_rig_parameter_changes_the_rig_not_the_model(tmp_path):
    base = scenarios.run("pam-ukf", quick=True, fmu_dir=tmp_path)
    wide = scenarios.run("pam-ukf", quick=True, fmu_dir=tmp_path, params={"A1": 1.3 * PAM["A1"].value})
    # the model alone is open loop on the nominal Table II model: its torque error changes only
    # because the rig's truth does
    assert wide["model_only"]["angle"]["I"] != pytest.approx(base["model_only"]["angle"]["I"], rel=1e-3)
    assert wide["params"] == {"A1": 1.3 * PAM["A1"].value}


def test_bad_overrides_are_named():
    with pytest.raises(UnknownNameError, match="'A9'.*A1"):
        scenarios.run("pam-ukf", quick=True, params={"A9": 1.0})
    with pytest.raises(ParameterError, match="segment_s"):
        scenarios.run("pam-ukf", quick=True, params={"segment_s": 0.01})
    with pytest.raises(ParameterError, match="'kpid' takes no parameters"):
        scenarios.run("kpid", quick=True, params={"Kp": 1.0})
    with pytest.raises(UnknownNameError, match="'k_x'.*k_s"):
        scenarios.run("exo-lqi", quick=True, params={"k_x": 1.0})
