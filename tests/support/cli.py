"""Run the `bsdflab` command line in a subprocess and check how it fails."""
from __future__ import annotations

import os
import subprocess
import sys

BSDFLAB = [sys.executable, "-m", "bsdflab.cli.main"]


def cli(*args, timeout=300, env=None) -> subprocess.CompletedProcess:
    """`bsdflab ARGS...` with captured text output (``env`` adds to the environment)."""
    return subprocess.run([*BSDFLAB, *args], capture_output=True, text=True, timeout=timeout,
                          env={**os.environ, **(env or {})})


def one_line_error(result, *words) -> None:
    """A clean CLI failure: exit 2, one line on stderr naming the problem, no traceback."""
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert result.returncode == 2, (result.returncode, result.stderr[-2000:])
    assert len(lines) == 1 and "Traceback" not in result.stderr, result.stderr[-2000:]
    for word in words:
        assert word in lines[0], (word, lines[0])
