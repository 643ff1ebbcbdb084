"""The search tests fly the paper's missions, whose plans hold items the simulator skips with a warning."""
import warnings

import pytest


@pytest.fixture(autouse=True)
def _quiet():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        yield
