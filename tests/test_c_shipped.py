"""Shipping compiled libraries between processes (bondgraph.numerics.c_shipped): what a recording keeps,
and what installing a bundle registers -- once, only on the platform it was built for."""
import pytest

from bondgraph.numerics import c_build, c_shipped
from plants import library
from bondgraph.numerics.evaluate import compile_model

needs_cc = pytest.mark.skipif(c_build.find_compiler() is None, reason="no C compiler")


@pytest.fixture
def fresh_registry(monkeypatch, tmp_path):
    """This test's installs go to its own registry and directory, and vanish after it."""
    monkeypatch.setattr(c_shipped, "_INSTALLED", {})
    monkeypatch.setattr(c_shipped, "_BUNDLES", set())
    monkeypatch.setattr(c_shipped, "shipped_dir", lambda: tmp_path / "shipped")


@needs_cc
def test_a_recording_keeps_the_libraries_even_when_already_loaded(fresh_registry):
    eqs = library.build("mass-spring-damper").equations()
    compile_model(eqs, backend="c")                       # loaded before the recording opens
    with c_shipped.recording() as rec:
        compile_model(eqs, backend="c")
    bundle = rec.bundle()
    key = c_build.equations_key(eqs, "main")
    assert list(bundle.keys) == [key]
    assert bundle.libraries[bundle.keys[key]] == c_build.build_library(eqs).path.read_bytes()
    assert c_shipped.lookup(key) is None                   # recorded, not installed

    assert bundle.install() == 1 and bundle.install() == 0
    shipped = c_shipped.lookup(key)
    assert shipped.parent == c_shipped.shipped_dir() and shipped.read_bytes() == bundle.libraries[bundle.keys[key]]
    assert c_build.build_library(eqs).path == shipped       # looked up before any compiler or cache


def test_a_bundle_from_another_platform_installs_nothing(fresh_registry):
    bundle = c_shipped.KernelBundle({"ab" * 20: b"\x7fELF"}, {"eqs:x": "ab" * 20}, platform="plan9-mips")
    assert bundle.install() == 0 and c_shipped.lookup("eqs:x") is None
    assert not c_shipped.shipped_dir().exists()
