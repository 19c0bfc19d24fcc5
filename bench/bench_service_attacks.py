"""The second red team's heaviest mix (issue 33), bounded and on loopback only: /healthz
latency, the server's peak memory and the 5xx count while hostile requests run.

One run starts a real ``bsdflab serve`` on 127.0.0.1 (a free port, connection cap 40) and,
for ``--seconds`` each, several attackers at once, every loop bounded by count and time:
  bodies    8 clients posting 300 KB ``{"wi": [[], [], ...]}`` to /v1/bsdf/eval and /v1/tables (M3)
  methods   random 8-character HTTP methods without a key (M5)
  refs      eval requests naming 17 store references each (M4, refused by count)
  idle      40 idle sockets plus 4 that trickle their headers a byte a second (M11)
  uploads   8 concurrent 16 MiB chunked uploads of junk (M6)
  renders   furnace renders with subdivisions 2048 against a full queue (M8)
  heavy     8 clients of layered evaluations (the pool's 429s)
while a prober GETs /healthz every 20 ms on its own connection, in its own process (with
``--probe-thread``, as before, on a thread of this process: it then waits for this
process's GIL behind some thirty attacker threads, which the server is not to blame for).
``--loop-debug`` runs the server with ``PYTHONASYNCIODEBUG=1`` and prints the callbacks
that held its event loop longest (asyncio's slow-callback log, over 100 ms). Printed: requests sent,
the status counts (5xx other than the 503s of the connection cap, which every path but
/healthz answers while the 40 idle sockets are open, must be 0), /healthz p50 / p99 / max
and how many answered 200, and the server's peak resident memory (VmHWM). Run ``--python`` with another interpreter to
measure another checkout the same way; ``--attackers`` picks a subset.

    python bench/bench_service_attacks.py --seconds 20
    python bench/bench_service_attacks.py --seconds 20 --attackers uploads --loop-debug   # who blocks the loop
"""
from __future__ import annotations

import argparse
import collections
import json
import multiprocessing
import os
import random
import re
import socket
import string
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import httpx2 as httpx


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def vm_hwm_kib(pid: int) -> int:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmHWM:"):
            return int(line.split()[1])
    return 0


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=20.0, help="length of the attack")
    parser.add_argument("--python", default=sys.executable, help="interpreter whose bsdflab serves")
    parser.add_argument("--attackers", default=None,
                        help="comma-separated subset of bodies,methods,refs,idle,uploads,renders,heavy "
                             "(default all; 'none': the prober alone, the same machine's idle figures)")
    parser.add_argument("--probe-thread", action="store_true",
                        help="probe /healthz from a thread of this process (as before), not its own process")
    parser.add_argument("--loop-debug", action="store_true",
                        help="PYTHONASYNCIODEBUG=1 for the server; print its slowest event-loop callbacks")
    args = parser.parse_args()
    port, data = free_port(), tempfile.mkdtemp(prefix="bsdflab-attacks-")
    url = f"http://127.0.0.1:{port}"
    env = {**os.environ, "BSDFLAB_SERVER_LIMIT_CONCURRENCY": "40", "BSDFLAB_LIMIT_QUEUE": "4",
           "BSDFLAB_HEAVY_CONCURRENCY": "2", "BSDFLAB_LOG_LEVEL": "warning"}
    if args.loop_debug:
        env["PYTHONASYNCIODEBUG"] = "1"
    server = subprocess.Popen([args.python, "-m", "bsdflab.cli.main", "serve", "--port", str(port), "--data-dir",
                               data, "--workers", "1"], env=env, cwd=data, stdout=subprocess.DEVNULL,
                              stderr=open(Path(data) / "server.log", "w"))
    try:
        end = time.monotonic() + 120
        while time.monotonic() < end:
            try:
                if httpx.get(f"{url}/healthz", timeout=2).status_code == 200:
                    break
            except httpx.HTTPError:
                time.sleep(0.2)
        chosen = None if args.attackers is None else [a for a in args.attackers.split(",") if a != "none"]
        return attack(url, server.pid, args.seconds, chosen, not args.probe_thread)
    finally:
        server.terminate()
        server.wait(60)
        if args.loop_debug:
            slow_callbacks(Path(data) / "server.log")


def slow_callbacks(log: Path, top: int = 8) -> None:
    """The event loop's slow callbacks in the server's log (asyncio debug mode)."""
    found = []
    for line in log.read_text(errors="replace").splitlines():
        m = re.search(r"Executing (.*) took ([0-9.]+) seconds", line)
        if m:
            found.append((float(m.group(2)), m.group(1)[:300]))
    found.sort(reverse=True)
    print(f"slow event-loop callbacks (> 100 ms): {len(found)}, total {sum(t for t, _ in found):.2f} s")
    for t, what in found[:top]:
        print(f"  {1000 * t:.0f} ms  {what}")


def attack(url: str, pid: int, seconds: float, chosen: list[str] | None = None, probe_process: bool = True) -> int:
    return Attack(url, pid, chosen, probe_process).run(seconds)


def probe_main(url: str, stop, out) -> None:
    """The prober in its own process: /healthz every 20 ms until ``stop``; sends
    (latencies, answered 200) back on ``out``."""
    health, ok = [], 0
    with httpx.Client(base_url=url, timeout=60) as client:
        while not stop.is_set():
            start = time.perf_counter()
            try:
                ok += client.get("/healthz").status_code == 200
            except httpx.HTTPError:
                pass
            health.append(time.perf_counter() - start)
            time.sleep(0.02)
    out.send((health, ok))


class Attack:
    """The shared counters, lock and stop event of one run, one method per kind of thread."""

    def __init__(self, url: str, pid: int, chosen: list[str] | None = None, probe_process: bool = True) -> None:
        self.url, self.pid, self.probe_process = url, pid, probe_process
        self.statuses: collections.Counter[int | str] = collections.Counter()
        self.lock, self.stop = threading.Lock(), threading.Event()
        self.health: list[float] = []
        self.health_ok = 0
        groups = self.groups()
        self.hostile = set(groups) | {"idle"} if chosen is None else set(chosen)
        self.attackers = [a for name, group in groups.items() if name in self.hostile for a in group]
        self.host, self.port = url.rsplit(":", 1)[0].split("//")[1], int(url.rsplit(":", 1)[1])

    @staticmethod
    def groups() -> dict[str, list]:
        empty = json.dumps({"model": {"type": "diffuse", "reflectance": 0.5}, "wi": [[]] * 100_000,
                            "wo": [[0, 0, 1]]})
        table = json.dumps({"model": {"type": "diffuse", "reflectance": 0.5}, "wavelengths": [[]] * 100_000})
        ref = {"type": "measured", "hash": "0" * 64}
        refs = {"model": {"type": "layered", "interfaces": [ref] * 17, "slabs": [{}] * 17, "base": ref},
                "theta_i": [0], "theta_o": [0]}
        heavy = {"preset": "xenopeltis", "theta_i": [30], "theta_o": [40], "samples": 4096}
        render = {"scene": "furnace", "options": {"subdivisions": 2048}, "width": 8, "height": 8, "spp": 1}
        junk = os.urandom(1 << 20)

        def chunks():
            for _ in range(16):
                yield junk

        return {
            "bodies": [lambda c: c.post("/v1/bsdf/eval", content=empty, headers={"content-type": "application/json"}),
                       lambda c: c.post("/v1/tables", content=table, headers={"content-type": "application/json"})] * 4,
            "methods": [lambda c: c.request("".join(random.choices(string.ascii_uppercase, k=8)), "/v1/jobs")] * 2,
            "refs": [lambda c: c.post("/v1/bsdf/eval", json=refs)] * 2,
            "uploads": [lambda c: c.post("/v1/measured", params={"format": "merl"}, content=chunks())] * 8,
            "renders": [lambda c: c.post("/v1/renders", json={**render, "seed": random.randrange(1 << 30)})] * 2,
            "heavy": [lambda c: c.post("/v1/bsdf/eval", json=heavy)] * 8,
        }

    def count(self, status) -> None:
        with self.lock:
            self.statuses[status] += 1

    def loop(self, send, limit=10_000) -> None:
        with httpx.Client(base_url=self.url, timeout=60) as client:
            for _ in range(limit):
                if self.stop.is_set():
                    return
                try:
                    self.count(send(client).status_code)
                except httpx.HTTPError as e:
                    self.count(type(e).__name__)

    def trickle(self) -> None:
        s = socket.create_connection((self.host, self.port))
        try:
            for byte in b"GET /v1/presets HTTP/1.1\r\nHost: x\r\n":
                if self.stop.is_set():
                    return
                s.sendall(bytes([byte]))
                time.sleep(1.0)
        except OSError:
            self.count("trickle closed by server")
        finally:
            s.close()

    def probe(self) -> None:
        with httpx.Client(base_url=self.url, timeout=60) as client:
            while not self.stop.is_set():
                start = time.perf_counter()
                try:
                    ok = client.get("/healthz").status_code == 200
                except httpx.HTTPError:
                    ok = False
                self.health.append(time.perf_counter() - start)
                self.health_ok += ok
                time.sleep(0.02)

    def run(self, seconds: float) -> int:
        idle = [socket.create_connection((self.host, self.port)) for _ in range(40 if "idle" in self.hostile else 0)]
        threads = [threading.Thread(target=self.loop, args=(a,)) for a in self.attackers]
        threads += [threading.Thread(target=self.trickle) for _ in range(4 if "idle" in self.hostile else 0)]
        prober = None
        if self.probe_process:
            ctx = multiprocessing.get_context("spawn")
            stop, (receive, send) = ctx.Event(), ctx.Pipe(duplex=False)
            prober = ctx.Process(target=probe_main, args=(self.url, stop, send))
            prober.start()
        else:
            threads += [threading.Thread(target=self.probe)]
        peak = 0
        for t in threads:
            t.start()
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            peak = max(peak, vm_hwm_kib(self.pid))
            time.sleep(0.25)
        self.stop.set()
        if prober is not None:
            stop.set()
            self.health, self.health_ok = receive.recv()
            prober.join(30)
        for t in threads:
            t.join(120)
        peak = max(peak, vm_hwm_kib(self.pid))
        for s in idle:
            s.close()
        self.report(peak)
        return 0

    def report(self, peak: int) -> None:
        statuses, h = self.statuses, sorted(self.health)

        def p(q: float) -> float:
            return 1000 * h[min(len(h) - 1, int(q * len(h)))]

        fives = sum(n for s, n in statuses.items() if isinstance(s, int) and s >= 500 and s != 503)
        print(f"requests: {sum(statuses.values())}  statuses: {dict(sorted(statuses.items(), key=str))}")
        print(f"5xx other than the connection cap's 503: {fives}")
        where = "own process" if self.probe_process else "thread of the attackers' process"
        print(f"/healthz ({where}): {len(h)} probes, {self.health_ok} answered 200; p50 {p(0.5):.1f} ms, "
              f"p99 {p(0.99):.1f} ms, max {1000 * h[-1]:.1f} ms")
        print(f"server peak RSS (VmHWM): {peak / 1024:.0f} MiB")


if __name__ == "__main__":
    sys.exit(main())
