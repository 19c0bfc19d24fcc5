"""A real ``bsdflab serve`` under more heavy requests than its heavy pool: health answers
while every slot computes, the excess gets 429 with Retry-After, nothing 5xx, memory stays bounded;
a request whose client leaves stops computing (the deadline: test_heavy_pool.py).
Loopback only, bounded loops (docs/service.md, "Bounded work")."""
from __future__ import annotations

import json
import os
import socket
import threading
import time
from concurrent.futures import ThreadPoolExecutor

import httpx2 as httpx
import pytest
from prometheus_client.parser import text_string_to_metric_families

from support.liveness import HANG_S, wait_until
from support.service_process import ServiceProcess, wait_state

HEAVY = 2
# one pair of the layered preset at 16 384 walks: about a CPU-second, within every limit
HEAVY_EVAL = {"preset": "xenopeltis", "theta_i": [30], "theta_o": [40], "samples": 16_384}
# 16 pairs: about 16 CPU-seconds
LONG_EVAL = {"preset": "xenopeltis", "theta_i": [30], "theta_o": [float(x) for x in range(5, 85, 5)],
             "samples": 16_384}
# 600 pairs: ~600 CPU-seconds, for the slots to stay busy while the test looks (the module's
# server allows that many walks; the default limit is 2^18)
ENDLESS_EVAL = {**LONG_EVAL, "theta_o": [5.0 + 80.0 * k / 599 for k in range(600)]}
ENDLESS_WALKS = 600 * 16_384


def rss_mib(pid: int) -> float:
    with open(f"/proc/{pid}/status") as f:
        return next(int(line.split()[1]) for line in f if line.startswith("VmRSS:")) / 1024


def cpu_s(pid: int) -> float:
    fields = open(f"/proc/{pid}/stat").read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    s = ServiceProcess(tmp_path_factory.mktemp("saturation"), log_level="info", env={
        "BSDFLAB_HEAVY_CONCURRENCY": str(HEAVY), "BSDFLAB_COMPUTE_DEADLINE_S": str(int(HANG_S)), "BSDFLAB_THREADS": "1",
        "BSDFLAB_LIMIT_WALKS": str(ENDLESS_WALKS)})
    yield s
    s.stop()


def metric(url: str, name: str, **labels: str) -> float:
    """The sum of the server's /metrics samples called ``name`` with these labels."""
    text = httpx.get(f"{url}/metrics", timeout=HANG_S).text
    return sum(sample.value for family in text_string_to_metric_families(text) for sample in family.samples
               if sample.name == name and all(sample.labels.get(k) == v for k, v in labels.items()))


def evals_ended(url: str, status: str | None = None) -> float:
    """How many /v1/bsdf/eval requests the server has finished (with ``status``)."""
    labels = {"route": "/v1/bsdf/eval"} | ({"status": status} if status else {})
    return metric(url, "bsdflab_http_request_duration_seconds_count", **labels)


def open_eval(port: int, body: dict) -> socket.socket:
    """POST /v1/bsdf/eval on a raw socket that stays open: the server computes until it
    answers or this socket closes (httpx cannot leave a request at a moment of the test's
    choosing without a clock)."""
    payload = json.dumps(body).encode()
    s = socket.create_connection(("127.0.0.1", port), timeout=HANG_S)
    s.sendall(b"POST /v1/bsdf/eval HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: application/json\r\n"
              b"Content-Length: %d\r\n\r\n" % len(payload) + payload)
    return s


def answered(s: socket.socket) -> bool:
    s.setblocking(False)
    try:
        return s.recv(1, socket.MSG_PEEK) != b""   # b"": closed without an answer
    except BlockingIOError:
        return False
    finally:
        s.setblocking(True)


def computing(url: str, sockets: list[socket.socket]) -> bool:
    """Every heavy slot busy; an answer to one of ``sockets`` first (a refusal, a deadline)
    fails at once instead of waiting for a pool that will never fill."""
    assert not any(answered(s) for s in sockets), [s.recv(2000) for s in sockets if answered(s)]
    return metric(url, "bsdflab_heavy_in_flight") == HEAVY


def test_the_excess_gets_429_and_memory_stays_bounded(server):
    """Three bursts of 16 heavy requests on HEAVY slots: nothing but 200 and 429 (with
    Retry-After), at least HEAVY answered, health answering 200 throughout, memory bounded.
    Before: every heavy request queued instead of being refused."""
    pid = server.process.pid
    httpx.post(f"{server.url}/v1/bsdf/eval", json=HEAVY_EVAL, timeout=HANG_S)   # warm the model cache
    rss_before = rss_mib(pid)
    health, stop = [], threading.Event()

    def probe():
        with httpx.Client(timeout=HANG_S) as c:
            while not stop.is_set():
                health.append(c.get(f"{server.url}/healthz").status_code)
                time.sleep(0.02)

    def heavy(_):
        r = httpx.post(f"{server.url}/v1/bsdf/eval", json=HEAVY_EVAL, timeout=HANG_S)
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
    rss_after = rss_mib(pid)
    print(f"\nheavy requests {len(codes)}: 200 x{codes.count(200)}, 429 x{codes.count(429)}; "
          f"/healthz {len(health)} probes; RSS {rss_before:.0f} -> {rss_after:.0f} MiB")
    assert set(codes) <= {200, 429} and codes.count(429) > 0 and codes.count(200) >= HEAVY
    assert all(retry is not None and int(retry) >= 1 for code, retry in answers if code == 429)
    assert health and all(status == 200 for status in health)
    assert rss_after - rss_before < 300


def test_health_answers_while_every_slot_computes(server):
    """Health never waits on computation, shown by order, not by a clock: with every heavy
    slot computing a request of ~600 CPU-seconds (600 pairs), /healthz answers 200, and
    afterwards every slot is still busy and no computing request has an answer. Before:
    /healthz shared the request thread pool with evaluations (48 heavy requests delayed it
    10-17 s). Mutation caught: /healthz awaiting a heavy slot (429 while they are full)."""
    ended = evals_ended(server.url)
    sockets = [open_eval(server.port, {**ENDLESS_EVAL, "seed": 20 + k}) for k in range(HEAVY)]
    try:
        wait_until(lambda: computing(server.url, sockets), "full heavy pool")
        assert httpx.get(f"{server.url}/healthz", timeout=HANG_S).status_code == 200
        assert metric(server.url, "bsdflab_heavy_in_flight") == HEAVY
        assert not any(answered(s) for s in sockets)
    finally:
        for s in sockets:
            s.close()
    # the leaving clients cancel their work (the next test's subject): the slots are free again
    wait_until(lambda: evals_ended(server.url) >= ended + HEAVY, "end of the cancelled requests")
    assert evals_ended(server.url, "499") >= HEAVY


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
    wait_until(lambda: marker in server.output(), f"log line {marker}")


def test_a_client_that_leaves_cancels_its_computation(server):
    """CPU-seconds, not a clock: two clients send 16 CPU-seconds of walks each and leave;
    once the server has ended both requests (with 499, "client closed"), its process has
    spent far less than their 32 CPU-seconds. Before: 8 clients that timed out left 9.5
    CPU-seconds of work running. The module's compute deadline (HANG_S) is far beyond, so
    only the client's leaving can stop the work. Mutation caught: heavy.py not setting
    ``stop`` on a disconnect (the requests end with 200 after all their walks)."""
    pid = server.process.pid
    ended, before = evals_ended(server.url), cpu_s(pid)
    sockets = [open_eval(server.port, {**LONG_EVAL, "seed": seed}) for seed in range(HEAVY)]
    wait_until(lambda: computing(server.url, sockets), "both requests computing")
    for s in sockets:
        s.close()
    wait_until(lambda: evals_ended(server.url) >= ended + HEAVY, "end of both requests")
    used = cpu_s(pid) - before
    print(f"\nCPU-seconds the server spent on the two requests: {used:.2f} (uncancelled: ~32)")
    assert evals_ended(server.url, "499") >= HEAVY
    # each request's walks go on to the end of their current C++ call (about a CPU-second)
    assert used < 8.0
    assert httpx.get(f"{server.url}/healthz", timeout=HANG_S).status_code == 200
