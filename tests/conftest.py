"""Shared fixtures. Helpers that tests import live in tests/support/ (on the path through
pytest's ``pythonpath`` setting)."""
from __future__ import annotations

import numpy as np
import pytest


@pytest.fixture
def rng():
    return np.random.default_rng(12345)
