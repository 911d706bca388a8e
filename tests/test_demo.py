"""``bondcosim demo`` runs end to end on built-in defaults and writes what it says."""
from pathlib import Path

import pandas as pd
from fmpy.validation import validate_fmu

from bondcosim.cli import main


def test_demo_writes_every_file_it_lists(tmp_path, capsys):
    assert main(["demo", "--output-dir", str(tmp_path), "--quick"]) == 0
    out = capsys.readouterr().out
    summary = out.split("== done in", 1)[1].splitlines()[1:]   # the files, one per line
    assert len(summary) >= 15
    for line in summary:
        path = Path(line.strip())
        assert path.parent in (tmp_path, tmp_path / "diagnosis", tmp_path / "montecarlo"), line
        assert path.stat().st_size > 0, line
    assert "A, B, C, D equal eq. (3): True" in out
    assert "fmpy validation: no problems" in out
    assert "Missing physics: coulomb_friction at junction v_mass" in out   # the quick demo's case
    assert validate_fmu(str(tmp_path / "pam.fmu")) == []
    runs = pd.read_parquet(tmp_path / "montecarlo" / "runs.parquet")    # the quick demo's Monte-Carlo
    assert len(runs) == 4 and (runs["status"] == "ok").all()
    assert (runs["metric.ukf.angle.I"] < runs["metric.model_only.angle.I"]).all()   # the UKF helps on every rig
    assert (tmp_path / "montecarlo" / "metrics_histograms.png").exists()
