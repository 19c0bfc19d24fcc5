"""A real `bsdflab serve` process on 127.0.0.1 and a free port, for end-to-end tests."""
from __future__ import annotations

import json
import os
import random
import shutil
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import httpx2 as httpx

from support.liveness import HANG_S

# pytest-xdist's workers (PYTEST_XDIST_WORKER gw0, gw1, ...) each draw ports from a band of
# their own below Linux's ephemeral range (32768-60999): a port one worker has probed and not
# yet handed to its server cannot be taken by the other worker's probe, nor by any
# outgoing connection's local port. Without xdist, the kernel's free port.
_BAND_START, _BAND_SIZE = 20000, 1000


def free_port() -> int:
    """A port on 127.0.0.1 that was free when probed, and that no other test worker draws."""
    worker = os.environ.get("PYTEST_XDIST_WORKER", "")
    if not worker.startswith("gw"):
        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            return s.getsockname()[1]
    start = _BAND_START + int(worker[2:]) * _BAND_SIZE
    for port in random.Random().sample(range(start, start + _BAND_SIZE), _BAND_SIZE):
        with socket.socket() as s:
            try:
                s.bind(("127.0.0.1", port))
            except OSError:
                continue
            return port
    raise RuntimeError(f"no free port in {start}-{start + _BAND_SIZE - 1}")


def bsdflab_command() -> list[str]:
    script = Path(sys.executable).with_name("bsdflab")
    return [str(script)] if script.exists() else [shutil.which("bsdflab") or "bsdflab"]


class ServiceProcess:
    """``bsdflab serve`` in a subprocess; ``url`` once it answers /healthz."""

    def __init__(self, data_dir: Path, workers: int = 1, env: dict[str, str] | None = None,
                 log_level: str = "warning", cache_dir: Path | None = None):
        """``cache_dir``: the table cache (default ``data_dir/tables``: never the user's)."""
        self.data_dir, self.port = data_dir, free_port()
        self.cache_dir = cache_dir if cache_dir is not None else data_dir / "tables"
        self.url = f"http://127.0.0.1:{self.port}"
        self.log = open(data_dir / f"server-{self.port}.log", "w")
        self.process = subprocess.Popen(
            [*bsdflab_command(), "serve", "--port", str(self.port), "--data-dir", str(data_dir),
             "--cache-dir", str(self.cache_dir), "--workers", str(workers), "--log-level", log_level],
            stdout=self.log, stderr=subprocess.STDOUT, env={**os.environ, **(env or {})})
        self._wait_healthy()

    def _wait_healthy(self, timeout: float = HANG_S) -> None:
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            if self.process.poll() is not None:
                raise RuntimeError(f"bsdflab serve exited with {self.process.returncode}: {self.output()}")
            try:
                if httpx.get(f"{self.url}/healthz", timeout=2).status_code == 200:
                    return
            except httpx.HTTPError:
                pass
            time.sleep(0.1)
        raise RuntimeError(f"bsdflab serve did not start: {self.output()}")

    def output(self) -> str:
        self.log.flush()
        return (self.data_dir / f"server-{self.port}.log").read_text()[-4000:]

    def children(self) -> list[int]:
        """Process ids whose parent is the server (its job workers), from /proc."""
        found = []
        for entry in Path("/proc").iterdir():
            if entry.name.isdigit():
                try:
                    fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
                except OSError:
                    continue
                if int(fields[1]) == self.process.pid:
                    found.append(int(entry.name))
        return found

    def kill(self) -> None:
        """SIGKILL: no shutdown code runs."""
        self.process.send_signal(signal.SIGKILL)
        self.process.wait(30)
        self.log.close()

    def stop(self) -> None:
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGTERM)
            try:
                self.process.wait(30)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait(30)
        self.log.close()


def follow_events(url: str, job_id: str, timeout: float = 300.0) -> list[tuple[str, dict]]:
    """The job's server-sent events, (event name, job) pairs, until its final event."""
    events, name = [], None
    with httpx.stream("GET", f"{url}/v1/jobs/{job_id}/events", timeout=timeout) as response:
        assert response.status_code == 200 and response.headers["content-type"].startswith("text/event-stream")
        for line in response.iter_lines():
            if line.startswith("event:"):
                name = line.split(":", 1)[1].strip()
            elif line.startswith("data:"):
                events.append((name, json.loads(line.split(":", 1)[1])))
    return events


def wait_state(url: str, job_id: str, states, timeout: float = 300.0) -> dict:
    end = time.monotonic() + timeout
    while True:
        job = httpx.get(f"{url}/v1/jobs/{job_id}", timeout=HANG_S).json()
        if job["state"] in states:
            return job
        if time.monotonic() > end:
            raise AssertionError(f"job still {job['state']}: {job}")
        time.sleep(0.05)
