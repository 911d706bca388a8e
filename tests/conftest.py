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
