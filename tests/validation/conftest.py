"""The one `bsdflab validate --level quick` run of tests/validation, read by
test_validation_registry.py only (it holds every check to its row): under pytest-xdist a
session fixture is built once per worker that needs it, so one file uses it."""
from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest


@pytest.fixture(scope="session")
def quick_report(tmp_path_factory):
    """(process, results document, report folder) of `bsdflab validate --level quick`."""
    tmp = tmp_path_factory.mktemp("validate-quick")
    out = tmp / "report"
    env = dict(os.environ, BSDFLAB_CACHE_DIR=str(tmp / "cache"))
    proc = subprocess.run([sys.executable, "-m", "bsdflab.cli.main", "validate", "--level", "quick",
                           "--out", str(out), "--quiet"], capture_output=True, text=True, timeout=900, env=env)
    assert (out / "results.json").exists(), proc.stderr[-3000:]
    return proc, json.loads((out / "results.json").read_text()), out
