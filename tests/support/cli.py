"""Run the `bsdflab` command line in a subprocess and check how it fails."""
from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
import threading
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


def interrupt_when(proc: subprocess.Popen, marker: bytes, cpu_after: float = 0.0,
                   hang_s: float = 300) -> tuple[int, str]:
    """SIGINT to `proc` once `marker` has appeared on its stderr (a binary pipe) and it has
    spent `cpu_after` more CPU-seconds; returns (exit status, the whole of stderr).

    One thread reads all of stderr. Before, the fit's test read the start through the text
    wrapper and the rest with communicate(), which reads the raw pipe: what the wrapper had
    buffered was lost, and the rest could begin mid-line (a bar's tail such as "s]"), a
    stray line under load. `hang_s` only bounds a hang."""
    seen = threading.Event()
    chunks: list[bytes] = []

    def read():
        start = b""
        while chunk := proc.stderr.read1(4096):
            chunks.append(chunk)
            if not seen.is_set():
                start += chunk
                if marker in start:
                    seen.set()
        seen.set()  # EOF: the process ended; the check below reports it

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    while not seen.wait(0.05):  # polling for a hang, not a synchronisation
        pass
    assert proc.poll() is None and marker in b"".join(chunks), \
        f"the process ended before {marker!r}: {b''.join(chunks)[-2000:]!r}"
    if cpu_after:
        wait_for_cpu(proc, cpu_after, b"".join(chunks)[-2000:])
    proc.send_signal(signal.SIGINT)
    status = proc.wait(hang_s)
    reader.join(hang_s)
    return status, b"".join(chunks).decode(errors="replace")


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
