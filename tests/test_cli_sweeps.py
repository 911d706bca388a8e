"""``bondcosim montecarlo``, ``sweep`` and ``diagnose-batch`` in-process (serial: ``--workers 0``)."""
import json

import pandas as pd
import pytest

from bondcosim.cli import main
import reproductions as scenarios


def test_montecarlo_writes_one_row_per_run_and_its_plots(tmp_path, capsys):
    out = tmp_path / "mc"
    code = main(["montecarlo", "pam-ukf", "--samples", "2", "--vary", "A1=normal(1,0.1)*nominal",
                 "--set", "sigma_p=5000", "--quick", "--seed", "3", "--out", str(out), "--workers", "0"])
    assert code == 0
    table = pd.read_parquet(out / "runs.parquet")
    assert table["run_id"].tolist() == [0, 1] and (table["status"] == "ok").all()
    row = table.iloc[0]
    direct = scenarios.run("pam-ukf", quick=True, params={"A1": row["param.A1"], "sigma_p": 5000.0},
                           seed=int(row["seed"]))
    assert row["metric.ukf.angle.I"] == direct["ukf"]["angle"]["I"] and row["metric.noise_sigma_pa"] == 5000.0
    text = capsys.readouterr().out
    assert "montecarlo-pam-ukf: 2 runs, 2 ok, 0 failed" in text and "ukf.angle.I" in text
    assert (out / "metrics_histograms.png").exists() and json.loads((out / "summary.json").read_text())["n_ok"] == 2


def test_sweep_spec_grid_gives_a_heat_map_and_resumes_to_nothing(tmp_path, capsys):
    spec = tmp_path / "grid.toml"
    spec.write_text('name = "msd-grid"\nmetrics = ["x.max", "v.rms"]\n'
                    '[model]\nname = "mass-spring-damper"\nstop_time = 10.0\noutput_interval = 0.05\n'
                    'inputs = { F = "2" }\noutputs = ["x"]\n'
                    '[vary]\nk = "linspace(0.5, 1.5, 3)*nominal"\nb = [0.2, 0.8]\n')
    out = tmp_path / "grid"
    assert main(["sweep", str(spec), "--out", str(out), "--workers", "0"]) == 0
    table = pd.read_parquet(out / "runs.parquet")
    assert len(table) == 6 and sorted(table["param.k"].unique()) == [2.0, 4.0, 6.0]   # nominal k = 4 N/m
    assert len(table["output.x"].iloc[0]) == len(table["output.t"].iloc[0]) == 201
    # F = 2 N on the spring: the static deflection F/k is where x settles, overshooting with little damping
    assert table["metric.x.max"].min() > 2.0 / 6.0
    assert (out / "heatmap_x_max.png").exists()
    capsys.readouterr()
    assert main(["sweep", str(spec), "--out", str(out), "--workers", "0", "--resume"]) == 0
    assert "(0 run now, 6 resumed" in capsys.readouterr().out


@pytest.mark.parametrize("argv, needle", [
    (["montecarlo", "pam-ukf", "--samples", "2", "--vary", "A1=normal(1)"], "parameter 'A1': cannot read"),
    (["montecarlo", "pam-ukf", "--samples", "2", "--vary", "A9=normal(1,0.1)"], "has no parameter 'A9'"),
    (["montecarlo", "pam-ukf", "--samples", "2", "--vary", "A1=normal(1,0.1)", "--set", "k1=x"], "--set"),
    (["montecarlo", "nope", "--samples", "2", "--vary", "A1=normal(1,0.1)"], "unknown scenario 'nope'"),
    (["sweep", "missing.toml"], "missing.toml: 1 problem(s)"),
])
def test_bad_sweep_input_is_one_line_naming_it(tmp_path, capsys, argv, needle):
    assert main(argv + ["--out", str(tmp_path / "o"), "--workers", "0"]) == 1
    err = capsys.readouterr().err
    assert needle in err and "Traceback" not in err


def test_diagnose_batch_summarises_the_fleet(tmp_path, capsys):
    from diagnosis.cases import case
    from diagnosis.cases.generate import manifest_entry, write_case
    recs = tmp_path / "recordings"
    recs.mkdir()
    for name in ("msd_coulomb", "msd_null"):       # diagnosis/cases: hidden Coulomb friction, and none
        csv, rec = write_case(case(name), tmp_path)
        entry = manifest_entry(case(name), rec)
        frame = pd.read_csv(csv)
        frame[frame["t_s"] <= 12.0].to_csv(recs / f"{name}.csv", index=False)   # 12 s keep the test short
    pd.DataFrame({"t_s": [0.0, 0.1], "F_N": [0.0, 1.0]}).to_csv(recs / "unplugged.csv", index=False)
    out = tmp_path / "fleet"
    argv = ["diagnose-batch", "mass-spring-damper", str(recs / "*.csv"), "--time", entry["time"],
            "--max-effects", "1", "--top", "1", "--out", str(out), "--workers", "0"]
    for b in entry["inputs"]:
        argv += ["--input", b]
    for b in entry["outputs"]:
        argv += ["--output", b]
    assert main(argv) == 0
    summary = json.loads((out / "fleet_summary.json").read_text())
    assert summary["kinds"] == {"coulomb_friction": 1, "none": 1} and summary["n_failed"] == 1
    assert summary["places"] == {"coulomb_friction": {"junction v_mass": 1}}
    # the case's truth: F_c = 0.03 N (diagnosis/cases/definitions.py), fitted within 5 %
    assert summary["parameters"]["coulomb_friction"]["Fc_v_mass"]["median"] == pytest.approx(0.03, rel=0.05)
    assert summary["improvement_by_kind"]["coulomb_friction"]["median"] > 0.5
    assert "no column 'x_mm'" in summary["failed"][str((recs / "unplugged.csv").resolve())]
    text = capsys.readouterr().out
    assert "coulomb_friction: 1 recording(s) at junction v_mass" in text
    assert (out / "fleet_kinds.png").exists() and len(pd.read_parquet(out / "runs.parquet")) == 3


def test_sweep_of_a_python_model_file(tmp_path):
    model = tmp_path / "damped.py"
    model.write_text("from bondgraph import BondGraph, Se, I, R, One\n"
                     "def build():\n"
                     "    g = BondGraph('damped')\n"
                     "    for e in (Se('F', 1.0), One('j'), I('m', 2.0), R('b', 0.5)):\n"
                     "        g.add(e)\n"
                     "    g.connect('F', 'j'); g.connect('j', 'm'); g.connect('j', 'b')\n"
                     "    g.add_output('v', 'p_m/m', unit='m/s')\n"
                     "    return g\n")
    spec = tmp_path / "s.yaml"
    spec.write_text(f"model:\n  name: {model}\n  stop_time: 40.0\nvary:\n  b: grid(0.5, 1.0)\nmetrics: [v.final]\n")
    assert main(["sweep", str(spec), "--out", str(tmp_path / "o"), "--workers", "0"]) == 0
    table = pd.read_parquet(tmp_path / "o" / "runs.parquet")
    # m dv/dt = F - b v: v -> F/b = 2 and 1 m/s (time constants m/b = 4 s and 2 s, 40 s = 10-20 of them)
    assert table["metric.v.final"].tolist() == pytest.approx([2.0, 1.0], rel=1e-4)
