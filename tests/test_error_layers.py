"""Errors by layer: one BondcosimError base, each class also a builtin, each layer raising its own
(bondgraph/errors.py, fmus/errors.py, estimators/errors.py, cosim/errors.py, diagnosis/errors.py)."""
from __future__ import annotations

import builtins
import importlib
import inspect
import re
from pathlib import Path

import pytest

from bondgraph.errors import BondcosimError

ROOT = Path(__file__).resolve().parents[1]
LAYERS = ("bondgraph", "plants", "fmus", "estimators", "cosim", "reproductions", "diagnosis")
BUILTIN_ERRORS = {c for c in vars(builtins).values() if isinstance(c, type) and issubclass(c, Exception)}


@pytest.mark.parametrize("layer", LAYERS)
def test_every_error_class_is_a_bondcosim_error_and_a_builtin(layer):
    module = importlib.import_module(f"{layer}.errors")
    classes = [c for c in vars(module).values() if inspect.isclass(c) and issubclass(c, Exception)]
    assert classes
    for cls in classes:
        assert issubclass(cls, BondcosimError), cls
        if cls is not BondcosimError:
            assert any(issubclass(cls, b) for b in BUILTIN_ERRORS - {Exception, BaseException}), cls


def test_existing_names_still_import_from_bondgraph_errors():
    from bondgraph import errors
    for name in ("FMUError", "CosimError", "AlgebraicLoopError", "EstimatorError", "UnobservableModeError",
                 "UncontrollableModeError", "CompilationError", "SimulationError"):
        assert getattr(errors, name) is getattr(importlib.import_module(
            {"FMUError": "fmus", "CompilationError": "fmus", "SimulationError": "cosim", "CosimError": "cosim",
             "AlgebraicLoopError": "cosim"}.get(name, "estimators") + ".errors"), name)


def _sources(layer):
    return [p for p in (ROOT / layer).rglob("*.py") if p.name != "errors.py"]


@pytest.mark.parametrize("layer", LAYERS + ("sweeps", "bondcosim"))
def test_no_plain_builtin_exception_is_raised(layer):
    plain = re.compile(r"raise (ValueError|TypeError|KeyError|IndexError|RuntimeError|OSError|Exception)\(")
    found = [f"{p.relative_to(ROOT)}:{i}" for p in _sources(layer)
             for i, line in enumerate(p.read_text(encoding="utf-8").splitlines(), 1) if plain.search(line)]
    assert found == []


@pytest.mark.parametrize("layer", ("plants", "fmus", "estimators", "cosim", "reproductions", "diagnosis"))
def test_each_layer_imports_its_errors_from_its_own_module(layer):
    found = [str(p.relative_to(ROOT)) for p in _sources(layer) if "from bondgraph.errors import" in p.read_text()]
    assert found == []
