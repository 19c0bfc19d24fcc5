"""The one `bsdflab validate --level quick` run of tests/validation, shared by both files:
test_validation_registry.py holds every check to its row, test_validation_families.py each
new family's checks (re-running them in-process doubled the quick level's ~100 s)."""
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
