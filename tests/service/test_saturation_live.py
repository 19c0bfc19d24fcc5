"""A real ``bsdflab serve`` under more heavy requests than its heavy pool: health answers at
once throughout, the excess gets 429 with Retry-After, nothing 5xx, memory stays bounded;
a request whose client leaves stops computing (the deadline: test_heavy_pool.py).
Loopback only, bounded loops (docs/service.md, "Bounded work")."""
from __future__ import annotations

import os
import threading
import time
from concurrent.futures import ThreadPoolExecutor

import httpx2 as httpx
import pytest

from support.service_process import ServiceProcess, wait_state

HEAVY = 2
# one pair of the layered preset at 16 384 walks: about a CPU-second, within every limit
HEAVY_EVAL = {"preset": "xenopeltis", "theta_i": [30], "theta_o": [40], "samples": 16_384}
# 16 pairs: about 16 CPU-seconds
LONG_EVAL = {"preset": "xenopeltis", "theta_i": [30], "theta_o": [float(x) for x in range(5, 85, 5)],
             "samples": 16_384}


def rss_mib(pid: int) -> float:
    with open(f"/proc/{pid}/status") as f:
        return next(int(line.split()[1]) for line in f if line.startswith("VmRSS:")) / 1024


def cpu_s(pid: int) -> float:
    fields = open(f"/proc/{pid}/stat").read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    s = ServiceProcess(tmp_path_factory.mktemp("saturation"), log_level="info", env={
        "BSDFLAB_HEAVY_CONCURRENCY": str(HEAVY), "BSDFLAB_COMPUTE_DEADLINE_S": "60", "BSDFLAB_THREADS": "1"})
    yield s
    s.stop()


def test_health_never_starves_and_the_excess_gets_429(server):
    """Before: /healthz shared the request thread pool with evaluations (48 heavy requests
    delayed it 10-17 s), and every heavy request queued instead of being refused."""
    pid = server.process.pid
    httpx.post(f"{server.url}/v1/bsdf/eval", json=HEAVY_EVAL, timeout=60)   # warm the model cache
    rss_before = rss_mib(pid)
    health, stop = [], threading.Event()

    def probe():
        with httpx.Client(timeout=10) as c:
            while not stop.is_set():
                t = time.perf_counter()
                status = c.get(f"{server.url}/healthz").status_code
                health.append((status, time.perf_counter() - t))
                time.sleep(0.02)

    def heavy(_):
        r = httpx.post(f"{server.url}/v1/bsdf/eval", json=HEAVY_EVAL, timeout=60)
        return r.status_code, r.headers.get("retry-after")

    prober = threading.Thread(target=probe)
    prober.start()
    try:
        with ThreadPoolExecutor(16) as pool:
            answers = [a for _ in range(3) for a in pool.map(heavy, range(16))]   # three bursts of 16
    finally:
        stop.set()
        prober.join()
    codes = [code for code, _ in answers]
    worst = max(t for _, t in health)
    rss_after = rss_mib(pid)
    print(f"\nheavy requests {len(codes)}: 200 x{codes.count(200)}, 429 x{codes.count(429)}; "
          f"/healthz {len(health)} probes, max {worst * 1000:.0f} ms; RSS {rss_before:.0f} -> {rss_after:.0f} MiB")
    assert set(codes) <= {200, 429} and codes.count(429) > 0 and codes.count(200) >= HEAVY
    assert all(retry is not None and int(retry) >= 1 for code, retry in answers if code == 429)
    assert all(status == 200 for status, _ in health) and worst < 1.0
    assert rss_after - rss_before < 300


def test_log_lines_survive_concurrent_table_requests(server):
    """Before: 32 concurrent table-model requests left the server's stdout and stderr on a
    deleted temporary file (process-wide dup2 from many threads): later lines were lost."""
    table = {"model": {"type": "diffuse", "reflectance": 0.5}, "grid": {"n_theta_i": 2, "n_theta_o": 4, "n_phi": 3}}
    job = httpx.post(f"{server.url}/v1/tables", json=table, timeout=60).json()
    wait_state(server.url, job["id"], ("done",))
    fd_targets = [os.readlink(f"/proc/{server.process.pid}/fd/{fd}") for fd in (1, 2)]

    def table_eval(i):
        body = {"model": {"type": "table", "hash": job["hash"], "film_lookup": bool(i % 2)},
                "theta_i": [10], "theta_o": [20 + i % 7]}
        return httpx.post(f"{server.url}/v1/bsdf/eval", json=body, timeout=60).status_code

    with ThreadPoolExecutor(32) as pool:
        codes = list(pool.map(table_eval, range(32)))
    assert set(codes) <= {200, 429}
    assert [os.readlink(f"/proc/{server.process.pid}/fd/{fd}") for fd in (1, 2)] == fd_targets
    marker = f"after-{job['id'][:8]}"
    httpx.get(f"{server.url}/healthz", headers={"X-Request-ID": marker})
    end = time.monotonic() + 10
    while marker not in server.output():
        assert time.monotonic() < end, server.output()[-2000:]
        time.sleep(0.1)


def test_a_client_that_leaves_cancels_its_computation(server):
    """Before: 8 clients that timed out left 9.5 CPU-seconds of work running. On the
    module's server (its 60 s deadline is far beyond the 7 s watched here, so only the
    client's leaving can stop the work; before: a server of its own, 3 CPU-s of start and
    stop). Mutation caught: heavy.py not setting ``stop`` on a disconnect (the walks go on:
    1.4 CPU-s in the 2 s, on a loaded machine)."""
    pid = server.process.pid
    for seed in range(HEAVY):
        with pytest.raises(httpx.TimeoutException):
            httpx.post(f"{server.url}/v1/bsdf/eval", json={**LONG_EVAL, "seed": seed}, timeout=0.5)
    time.sleep(5.0)          # the C++ call in progress ends (about a CPU-second, longer under load)
    before = cpu_s(pid)
    time.sleep(2.0)
    used = cpu_s(pid) - before
    print(f"\nCPU-seconds used in the 2 s after the clients left: {used:.2f}")
    # uncancelled, the 8 clients' remaining walks keep both cores busy (~4 CPU-s in 2 s)
    assert used < 1.0
    assert httpx.get(f"{server.url}/healthz", timeout=2).status_code == 200
