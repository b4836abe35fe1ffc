import importlib.util
import os
import sys

import pytest

# shared helpers, `from helpers import ...`: tests/helpers.py registered as the module "helpers".
# Not by putting tests/ on sys.path: its folders nlbeam/, continuation/, stochastic/ (no
# __init__.py) would then shadow the packages as namespace packages (an editable install finds
# them after the path entries; pytest runs with --import-mode=importlib).
# tests/exact_pwl.py (exact answers for a piecewise-linear stop) likewise, as "exact_pwl".
for _name in ("helpers", "exact_pwl"):
    _spec = importlib.util.spec_from_file_location(
        _name, os.path.join(os.path.dirname(os.path.abspath(__file__)), _name + ".py"))
    sys.modules[_name] = importlib.util.module_from_spec(_spec)
    _spec.loader.exec_module(sys.modules[_name])


@pytest.fixture(autouse=True)
def _numpy_errors_loud():
    import numpy as np
    with np.errstate(all="raise", under="ignore"):
        yield
