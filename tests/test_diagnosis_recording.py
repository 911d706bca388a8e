"""diagnosis.recording: reading CSVs, refusing bad ones by name, binding to a model."""
import numpy as np
import pytest

from plants import library
from bondgraph.errors import UnknownNameError
from diagnosis.errors import RecordingError, UnitError
from diagnosis.recording import Binding, Experiment, Recording, bind


def _write(path, text):
    path.write_text(text)
    return path


@pytest.fixture
def msd():
    return library.build("mass-spring-damper")


@pytest.fixture
def csv_file(tmp_path):
    t = np.array([0.0, 0.1, 0.25, 0.3, 0.5])         # uneven sampling is kept as is
    lines = ["time,force_N,pos_mm,vel"] + [f"{a},{2 * a},{1000 * a * a},{np.sin(a)}" for a in t]
    return _write(tmp_path / "rec.csv", "\n".join(lines) + "\n")


def test_csv_is_read_as_written(csv_file):
    rec = Recording.from_csv(csv_file)
    assert rec.time_name == "time"
    np.testing.assert_array_equal(rec.t, [0.0, 0.1, 0.25, 0.3, 0.5])
    assert list(rec.columns) == ["force_N", "pos_mm", "vel"]
    np.testing.assert_allclose(rec.columns["pos_mm"], 1000 * rec.t ** 2)
    assert rec.gaps == {} and rec.constant == [] and rec.notes() == []


def test_time_column_default_first_and_unit(tmp_path):
    path = _write(tmp_path / "a.csv", "stamp_ms,y\n0,1\n5,2\n10,4\n")
    assert Recording.from_csv(path).time_name == "stamp_ms"      # the first column
    rec = Recording.from_csv(path, time="stamp_ms:ms")
    np.testing.assert_allclose(rec.t, [0.0, 0.005, 0.010])


def test_bind_converts_to_model_units(csv_file, msd):
    rec = Recording.from_csv(csv_file)
    exp = bind(rec, msd, inputs=["F=force_N:N"], outputs={"x": "pos_mm:mm", "v": "vel"})
    np.testing.assert_allclose(exp.outputs["x"], rec.t ** 2)    # mm -> m: factor 1e-3
    np.testing.assert_allclose(exp.inputs["F"], 2 * rec.t)
    assert exp.units == {"F": "N", "x": "m", "v": "m/s"}
    exp2 = bind(rec, msd.equations(), inputs=[Binding("F", "force_N")], outputs="x=pos_mm:cm")
    np.testing.assert_allclose(exp2.outputs["x"], 10 * rec.t ** 2)   # cm -> m: factor 1e-2


def test_split_and_window_keep_absolute_times():
    t = np.linspace(0.0, 10.0, 101)
    exp = Experiment(t, {"F": t.copy()}, {"x": 2 * t}, {"F": "N", "x": "m"}, "arrays")
    train, held = exp.split(0.3)
    assert train.span == (0.0, pytest.approx(6.9)) and held.span == (pytest.approx(7.0), 10.0)
    assert train.t.size + held.t.size == t.size
    np.testing.assert_allclose(held.outputs["x"], 2 * held.t)
    w = exp.window(2.0, 3.0)
    assert w.span == (2.0, 3.0) and w.t.size == 11
    with pytest.raises(RecordingError, match="holdout must be a fraction"):
        exp.split(1.2)


def test_binding_parse():
    assert Binding.parse("psi=angle:deg") == Binding("psi", "angle", "deg")
    assert Binding.parse(" u1 = volts ") == Binding("u1", "volts", None)
    with pytest.raises(RecordingError, match="NAME=COLUMN"):
        Binding.parse("psi")


# -- refusals, each naming the offending thing ----------------------------------------

def test_missing_column_is_named(csv_file, msd):
    rec = Recording.from_csv(csv_file)
    with pytest.raises(UnknownNameError) as info:
        bind(rec, msd, inputs=["F=force"], outputs=["x=pos_mm:mm"])
    assert "'force'" in str(info.value) and "force_N, pos_mm, vel" in str(info.value)
    assert info.value.kind == "column" and isinstance(info.value, RecordingError)


def test_unknown_model_names_are_listed(csv_file, msd):
    rec = Recording.from_csv(csv_file)
    with pytest.raises(UnknownNameError, match=r"unknown output 'y'.*known outputs are x, v"):
        bind(rec, msd, inputs=["F=force_N"], outputs=["y=vel"])
    with pytest.raises(UnknownNameError, match=r"unknown input 'G'.*known inputs are F"):
        bind(rec, msd, inputs=["G=force_N"], outputs=["x=vel"])


def test_nan_gap_reported_and_refused_when_bound(tmp_path, msd):
    path = _write(tmp_path / "gap.csv", "t,F,x\n0,1,0\n1,1,\n2,1,nan\n3,1,0.5\n4,,0.7\n")
    rec = Recording.from_csv(path)
    assert rec.gaps == {"x": [(1, 2)], "F": [(4, 4)]}
    assert "column 'x' has NaN gaps at rows 1-2" in rec.notes()
    with pytest.raises(RecordingError) as info:
        bind(rec, msd, inputs=[], outputs=["x=x"])
    assert "'x'" in str(info.value) and "rows 1-2" in str(info.value)
    assert info.value.column == "x" and info.value.rows == [1, 2]


def test_non_increasing_time_names_rows(tmp_path):
    path = _write(tmp_path / "back.csv", "t,y\n0,1\n0.1,2\n0.1,3\n0.05,4\n")
    with pytest.raises(RecordingError) as info:
        Recording.from_csv(path)
    assert "'t' does not increase at row(s) 2-3" in str(info.value)
    assert info.value.rows == [2, 3]


def test_non_numeric_cell_names_column_and_row(tmp_path):
    path = _write(tmp_path / "text.csv", "t,y\n0,1\n1,two\n")
    with pytest.raises(RecordingError, match=r"column 'y', data row 1: 'two' is not a number"):
        Recording.from_csv(path)


def test_duplicate_and_ragged(tmp_path):
    with pytest.raises(RecordingError, match=r"duplicate column name\(s\) 'y'"):
        Recording.from_csv(_write(tmp_path / "d.csv", "t,y,y\n0,1,2\n1,2,3\n"))
    with pytest.raises(RecordingError, match="data row 1 has 2 cells, the header 3"):
        Recording.from_csv(_write(tmp_path / "r.csv", "t,y,z\n0,1,2\n1,2\n"))


def test_constant_output_is_refused(tmp_path, msd):
    rec = Recording.from_csv(_write(tmp_path / "c.csv", "t,F,x\n0,1,0.2\n1,1,0.2\n2,1,0.2\n"))
    assert rec.constant == ["F", "x"]
    with pytest.raises(RecordingError, match=r"column 'x' bound to output 'x' is constant"):
        bind(rec, msd, inputs=["F=F"], outputs=["x=x"])


def test_unknown_unit_is_named(csv_file, msd):
    rec = Recording.from_csv(csv_file)
    with pytest.raises(UnitError) as info:
        bind(rec, msd, inputs=["F=force_N:lbfx"], outputs=["x=pos_mm:mm"])
    assert "'lbfx'" in str(info.value) and "'force_N'" in str(info.value)
    with pytest.raises(UnitError, match=r"'pos_mm'.*incompatible dimensions"):
        bind(rec, msd, inputs=["F=force_N"], outputs=["x=pos_mm:deg"])
