"""plants.load, the one model loader (the command line and the diagnosis use it): a built-in
name, a .json graph file, a .py file with build(), or a graph; every bad input one clear error."""
from __future__ import annotations

import pytest

import plants
from bondgraph.io_json import save
from plants.errors import ArgumentTypeError, MissingFileError, ModelFileError, UnknownModelError


def _same_equations(a, b):
    ea, eb = a.equations(), b.equations()
    assert (str(ea.f), str(ea.h), ea.param_values) == (str(eb.f), str(eb.h), eb.param_values)


def test_a_name_gives_a_fresh_built_in_graph():
    first, second = plants.load("rlc"), plants.load("rlc")
    assert first is not second
    _same_equations(first, plants.build("rlc"))


def test_a_graph_is_returned_as_it_is():
    graph = plants.build("mass-spring-damper")
    assert plants.load(graph) is graph


def test_a_json_file_and_a_path_object(tmp_path):
    graph = plants.build("coupled-tanks")
    save(graph, tmp_path / "tanks.json")
    _same_equations(plants.load(str(tmp_path / "tanks.json")), graph)
    _same_equations(plants.load(tmp_path / "tanks.json"), graph)


def test_a_python_file_with_build(tmp_path):
    path = tmp_path / "mine.py"
    path.write_text("import plants\n\ndef build():\n    return plants.build('dc-motor').with_params(Jm=0.02)\n")
    loaded = plants.load(path)
    assert loaded.equations().param_values["Jm"] == 0.02


@pytest.mark.parametrize("source, error, message", [
    ("def build(:\n", ModelFileError, r"model file '.*bad\.py' failed to import: SyntaxError"),
    ("x = 1\n", ModelFileError, r"model file '.*bad\.py' defines no build\(\) function"),
    ("def build():\n    return 42\n", ModelFileError, r"build\(\) in '.*bad\.py' returned int, not a BondGraph"),
])
def test_a_bad_python_file_is_named(tmp_path, source, error, message):
    path = tmp_path / "bad.py"
    path.write_text(source)
    with pytest.raises(error, match=message) as info:
        plants.load(str(path))
    assert info.value.path == str(path) and isinstance(info.value, ValueError)


def test_unknown_names_missing_files_and_wrong_types():
    with pytest.raises(UnknownModelError, match=r"unknown model 'msd': not a built-in model "
                                                 r"\(mass-spring-damper, dc-motor, rlc, .*\), nor a \.json or \.py file"):
        plants.load("msd")
    with pytest.raises(ValueError):   # the builtin it refines
        plants.load("msd")
    with pytest.raises(MissingFileError, match=r"model file 'nowhere\.json' does not exist"):
        plants.load("nowhere.json")
    with pytest.raises(FileNotFoundError):
        plants.load("nowhere.py")
    with pytest.raises(ArgumentTypeError, match=r"model must be a BondGraph, .*; found int"):
        plants.load(3)
    with pytest.raises(UnknownModelError, match=r"no built-in model named 'msd'; available: mass-spring-damper"):
        plants.build("msd")
