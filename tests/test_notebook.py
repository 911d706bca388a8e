"""Notebook and data-ecosystem surfaces: _repr_svg_, _repr_latex_, to_pandas/to_xarray, progress lines."""
from __future__ import annotations

import sys

import numpy as np
import pytest

from plants import library
from bondgraph.numerics import simulate
from bondgraph.errors import OptionalDependencyError
from bondgraph.numerics.progress import Progress


@pytest.fixture(scope="module")
def result():
    return simulate(library.build("rlc"), (0.0, 0.01), output_interval=1e-4)


def test_to_pandas_and_to_xarray_carry_values_and_units(result):
    pytest.importorskip("pandas")
    pytest.importorskip("xarray")
    frame, data = result.to_pandas(), result.to_xarray()
    assert list(frame.columns) == list(result.names)
    np.testing.assert_array_equal(frame.index.to_numpy(), result.t)
    for name in result.names:
        np.testing.assert_array_equal(frame[name].to_numpy(), result[name])
        np.testing.assert_array_equal(data[name].to_numpy(), result[name])
        assert frame.attrs["units"][name] == result.units[name] == data[name].attrs["units"]
        assert data[name].attrs["kind"] == result.kinds[name]
    assert frame.attrs["units"]["t"] == "s" and data["t"].attrs["units"] == "s"


@pytest.mark.parametrize("method, package", [("to_pandas", "pandas"), ("to_xarray", "xarray")])
def test_missing_optional_package_is_named(result, method, package, monkeypatch):
    monkeypatch.setitem(sys.modules, package, None)     # import now fails
    with pytest.raises(OptionalDependencyError, match=f"needs {package}.*pip install {package}") as info:
        getattr(result, method)()
    assert isinstance(info.value, ImportError) and info.value.package == package


def test_graph_svg_and_equations_latex():
    graph = library.build("mass-spring-damper")
    svg = graph._repr_svg_()
    assert "<svg" in svg and svg.rstrip().endswith("</svg>")
    latex = graph.equations()._repr_latex_()
    assert latex.startswith("$\\begin{aligned}") and r"f_{m} &:= \frac{p_{m}}{m}" in latex


def test_simulate_progress_line_on_tqdm(capsys):
    simulate(library.build("rlc"), (0.0, 0.01), progress=True)
    err = capsys.readouterr().err
    assert "simulate rlc_series: 100.0 %  t = 0.01 s" in err and err.endswith("\n")


def test_progress_disabled_prints_nothing(capsys):
    bar = Progress(3, fmt="x {percentage:3.0f}%", enabled=False)
    bar.update_to(2)
    bar.close()
    assert capsys.readouterr().err == ""
