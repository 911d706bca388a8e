import os

import matplotlib
import pytest
from hypothesis import settings

matplotlib.use("Agg")

# pytest-xdist runs one worker per core already: the compiled loops stay on one thread there
# (bondgraph.numerics.threads; tests of the threaded paths set their own count)
if os.environ.get("PYTEST_XDIST_WORKER"):
    os.environ.setdefault("BONDCOSIM_THREADS", "1")

settings.register_profile("bondcosim", deadline=None, max_examples=25, derandomize=True)
settings.load_profile("bondcosim")


@pytest.fixture
def rng():
    import numpy as np
    return np.random.default_rng(20261122)


@pytest.fixture
def load_script():
    """Import a script of the repository (benchmarks/, examples/) by its relative path."""
    import importlib.util
    from pathlib import Path

    root = Path(__file__).resolve().parent.parent

    def load(relative: str):
        path = root / relative
        spec = importlib.util.spec_from_file_location(f"script_{path.stem}", path)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        return module
    return load


@pytest.fixture(scope="session")
def exported_fmu(tmp_path_factory):
    """`exported_fmu(model, version, **options)` -> path of the library model's FMU, exported once
    per test session (`fmus.export`'s options, e.g. ``fixed_step``): a PAM's export takes seconds,
    and eight test modules read the same few FMUs.  Tests read them and never change them."""
    from fmus import export
    import plants.library as library

    root = tmp_path_factory.mktemp("fmus")
    cache = {}

    def get(model, version=2, **options):
        key = (model, version, tuple(sorted(options.items())))
        if key not in cache:
            cache[key] = export(library.build(model), root / f"{model}-{version}-{len(cache)}.fmu",
                                fmi_version=version, **options)
        return cache[key]
    return get
