"""The service's tests keep their tables out of the user's cache: the server's table cache
is BSDFLAB_CACHE_DIR (or --cache-dir), which defaults to the CLI's."""
from __future__ import annotations

import os

import pytest

from bsdflab.tables.cache import ENV_VAR


@pytest.fixture(scope="session", autouse=True)
def table_cache(tmp_path_factory):
    before = os.environ.get(ENV_VAR)
    os.environ[ENV_VAR] = str(tmp_path_factory.mktemp("table-cache"))
    yield
    if before is None:
        os.environ.pop(ENV_VAR, None)
    else:
        os.environ[ENV_VAR] = before
