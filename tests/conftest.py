"""Shared fixtures. Helpers that tests import live in tests/support/ (on the path through
pytest's ``pythonpath`` setting)."""
from __future__ import annotations

import numpy as np
import pytest


@pytest.fixture
def rng():
    return np.random.default_rng(12345)


def pytest_collection_modifyitems(config, items):
    """Test files longest first (tests/support/scheduling.py: how ./dev.sh test spreads them)."""
    from support.scheduling import load_costs, longest_first

    items[:] = longest_first(items, load_costs())
