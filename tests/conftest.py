import warnings

import pytest


@pytest.fixture(autouse=True)
def _numpy_errors_loud():
    import numpy as np
    with np.errstate(all="raise", under="ignore"):
        yield
