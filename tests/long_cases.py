"""The marker of the long diagnosis cases, shared by the test files that have them."""
import os

import pytest

#: a diagnosis of a minute or more: run with BONDCOSIM_DIAGNOSIS_CASES=all, as the long end-to-end cases
LONG = pytest.mark.skipif(os.environ.get("BONDCOSIM_DIAGNOSIS_CASES", "") != "all",
                          reason="long diagnosis: BONDCOSIM_DIAGNOSIS_CASES=all runs it")
