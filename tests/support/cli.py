"""Run the `bsdflab` command line in a subprocess and check how it fails."""
from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
from collections.abc import Iterator

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


def cpu_seconds(pid: int) -> float:
    """User + system CPU time of a process so far (/proc/PID/stat fields 14 and 15)."""
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def wait_for_cpu(proc: subprocess.Popen, seconds: float, what: str = "") -> None:
    """Wait until the process has spent `seconds` more CPU time than now: proof that its
    work is under way whatever the machine's load (a wall-clock sleep proves nothing)."""
    import threading

    target = cpu_seconds(proc.pid) + seconds
    pause = threading.Event()
    while cpu_seconds(proc.pid) < target:
        assert proc.poll() is None, f"the process ended first {what}"
        pause.wait(0.05)  # polling the condition, not a synchronisation


def _default_sigint() -> None:
    signal.signal(signal.SIGINT, signal.SIG_DFL)


@contextlib.contextmanager
def interruptible(args, **kwargs) -> Iterator[subprocess.Popen]:
    """``Popen(args, **kwargs)`` for a test that sends SIGINT, killed at exit if still running.

    The child starts with SIGINT at its default disposition: a runner started with SIGINT
    ignored (a shell's background job, nohup) passes SIG_IGN on, Python then installs no
    handler, and the test's SIGINT was lost while the child ran on for hours after the
    test failed (a 2^28 spp render, seen under a background stress run)."""
    proc = subprocess.Popen(args, preexec_fn=_default_sigint, **kwargs)
    try:
        yield proc
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


def cli_in_process(capsys, monkeypatch, *args, env=None) -> subprocess.CompletedProcess:
    """`bsdflab ARGS...` run in this process (bsdflab.cli.main.main with a list, as tests call
    it), as a CompletedProcess (returncode, stdout, stderr): what ``cli`` answers, without a
    child's ~2-4 CPU-s of imports. ``env`` sets variables for the call (monkeypatch)."""
    from bsdflab.cli.main import main

    for key, value in (env or {}).items():
        monkeypatch.setenv(key, str(value))
    capsys.readouterr()
    status = main([str(a) for a in args])
    out, err = capsys.readouterr()
    return subprocess.CompletedProcess(["bsdflab", *map(str, args)], status, out, err)
