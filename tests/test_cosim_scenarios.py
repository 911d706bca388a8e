"""Scenarios of reproductions: seed plants exported as FMUs, closed loops in the master."""
import numpy as np
import pytest

from reproductions import pam_pi


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


@pytest.mark.parametrize("version", (2, 3))
def test_our_fmus_in_our_master_equal_the_python_model(tmp_path, version):
    """The exported pam FMU (FMI 2.0 and 3.0) driven by zero-order-hold tables in the
    master gives bondgraph.numerics.simulate's result with the same tables (same RK4 kernel)."""
    from bondgraph.numerics import simulate
    import plants.library as library
    from cosim import CoSimulation, FMUComponent, Table
    from fmus import export

    dt, n = 1e-3, 1500
    t = np.arange(n + 1) * dt
    u1 = 5.0 + 3.0 * np.sign(np.sin(2 * np.pi * t) + 1e-9)
    fmu = export(library.build("pam"), tmp_path / f"pam{version}.fmu", fmi_version=version)
    sim = CoSimulation(
        [Table("a", t, u1, unit="V", interpolation="hold"),
         Table("b", t, 10.0 - u1, unit="V", interpolation="hold"), FMUComponent(fmu, "plant")],
        [("a.y", "plant.u1"), ("b.y", "plant.u2")], step=dt)
    res = sim.run(n * dt)
    ref = simulate(library.build("pam"), (0.0, n * dt), output_interval=dt,
                      inputs={"u1": (t, u1), "u2": (t, 10.0 - u1)})
    assert np.ptp(ref["psi"]) > 10.0
    for name in ("psi", "P1", "P2", "tau"):
        scale = max(1.0, np.abs(ref[name]).max())
        assert np.allclose(res[f"plant.{name}"], ref[name], rtol=0, atol=1e-12 * scale), name
