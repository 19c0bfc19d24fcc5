"""One version: bsdflab/_version.py, the package root and the build metadata agree.

Mutation: bump either `version` in pyproject.toml or `__version__` in bsdflab/_version.py
alone and the test fails."""
from importlib.metadata import version
from pathlib import Path

import bsdflab
from bsdflab._version import __version__
from bsdflab.fit.config import tomllib
from support.cli import cli

ROOT = Path(__file__).resolve().parents[2]


def test_one_version_everywhere():
    declared = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"]
    assert __version__ == declared == bsdflab.__version__ == version("bsdflab")
    assert cli("--version").stdout.strip() == f"bsdflab {declared}"
