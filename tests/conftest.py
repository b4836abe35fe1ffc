import os
import sys

import pytest

# shared test helpers: ``from helpers import ...`` (tests/helpers.py)
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))


@pytest.fixture(autouse=True)
def _numpy_errors_loud():
    import numpy as np
    with np.errstate(all="raise", under="ignore"):
        yield
