import matplotlib
import pytest
from hypothesis import settings

matplotlib.use("Agg")

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
