"""The HTTP layer's cost: POST /v1/bsdf/eval against a trivial endpoint and the direct call.

One run starts a real `bsdflab serve` on 127.0.0.1 (a free port) and a load generator in a
second process that sends, with ``--concurrency`` connections, at most ``--requests``
requests per scenario (and stops after ``--seconds``):
  healthz   GET /healthz (the app's floor: routing, JSON, uvicorn)
  eval/M    POST /v1/bsdf/eval with 1000 direction pairs of model M
  big/json, big/npy   POST /v1/bsdf/eval with 100 000 pairs of a diffuse model, answered
                      as JSON and as .npy (Accept: application/x-npy)
  saturated           /healthz while 2 x the heavy pool's size of clients post layered
                      evaluations without pause (the excess gets 429)
and, in this process, the same evaluation through the Python API (``lobe_views.evaluate``
on the same arrays). Printed: throughput and p50/p99 latency per scenario, and the ratios
HTTP p50 / direct p50 (goal: < 2 for a 1000-pair request), eval p50 / healthz p50,
JSON / .npy for 100 000 pairs, /healthz p99 saturated / idle, and the heavy evaluations'
throughput at the concurrency cap with the share answered 429.
Models: "diffuse" (the cheapest evaluation: the HTTP cost at its most visible) and
"thinfilm" (a rough dielectric with the guanine film, spectral: a realistic query).

    python bench/bench_service.py                     # ~1 minute
    python bench/bench_service.py --requests 400 --concurrency 8
Profile the server side with: python -m cProfile -o serve.prof -m bsdflab.cli.main serve
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

PAIRS = 1000
BIG_PAIRS = 100_000
HEAVY_EVAL = {"preset": "xenopeltis", "theta_i": [30], "theta_o": [40], "samples": 4096}
MODELS = {
    "diffuse": {"type": "diffuse", "reflectance": [0.5, 0.4, 0.3]},
    "thinfilm": {"type": "roughdielectric", "alpha": 0.08, "int_ior": 1.5515, "ext_ior": 1.000277,
                 "film": [{"material": 1.83, "thickness_nm": 400.0}]},
}


def directions(n: int = PAIRS, seed: int = 1) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(2, n, 3))
    v /= np.linalg.norm(v, axis=2, keepdims=True)
    v[..., 2] = np.abs(v[..., 2])
    return v[0], v[1]


def stats(latencies: list[float], wall: float) -> dict:
    a = np.asarray(latencies)
    return {"requests": len(a), "per_s": len(a) / wall, "p50_ms": 1e3 * float(np.percentile(a, 50)),
            "p99_ms": 1e3 * float(np.percentile(a, 99))}


# -- the load generator (second process) ------------------------------------------------------
def load(url: str, requests: int, concurrency: int, seconds: float, heavy: int) -> dict:
    import httpx2 as httpx

    wi, wo = directions()
    bodies = {name: json.dumps({"model": m, "wi": wi.tolist(), "wo": wo.tolist()}) for name, m in MODELS.items()}
    results = {}
    with httpx.Client(base_url=url, timeout=60, limits=httpx.Limits(max_connections=concurrency)) as client:
        scenarios = [("healthz", lambda: client.get("/healthz"))]
        scenarios += [(f"eval/{name}", lambda b=body: client.post(
            "/v1/bsdf/eval", content=b, headers={"content-type": "application/json"})) for name, body in bodies.items()]
        for name, call in scenarios:
            for _ in range(3):            # warm the connections and the model cache
                call().raise_for_status()
            deadline = time.perf_counter() + seconds

            def one(_, deadline=deadline, call=call):
                if time.perf_counter() > deadline:
                    return None
                t = time.perf_counter()
                call().raise_for_status()
                return time.perf_counter() - t

            start = time.perf_counter()
            with ThreadPoolExecutor(concurrency) as pool:
                latencies = [x for x in pool.map(one, range(requests)) if x is not None]
            results[name] = stats(latencies, time.perf_counter() - start)
        results.update(big(client, min(requests, 10)))
        results.update(saturated(url, client, seconds, heavy))
    return results


def big(client, requests: int) -> dict:
    """100 000 pairs answered as JSON and as .npy, one request at a time."""
    body = json.dumps({"model": MODELS["diffuse"], "theta_i": [30.0],
                       "theta_o": np.linspace(0.0, 80.0, BIG_PAIRS).tolist()})
    out = {}
    for name, accept in (("big/json", "application/json"), ("big/npy", "application/x-npy")):
        latencies, size = [], 0
        start = time.perf_counter()
        for _ in range(requests):
            t = time.perf_counter()
            r = client.post("/v1/bsdf/eval", content=body, headers={"content-type": "application/json",
                                                                     "accept": accept})
            r.raise_for_status()
            latencies.append(time.perf_counter() - t)
            size = len(r.content)
        out[name] = {**stats(latencies, time.perf_counter() - start), "bytes": size}
    return out


def saturated(url: str, client, seconds: float, heavy_slots: int) -> dict:
    """/healthz latency while 2 x the heavy pool's size of clients keep it full."""
    import threading

    import httpx2 as httpx

    stop, codes, lock = threading.Event(), {"200": 0, "429": 0, "other": 0}, threading.Lock()

    def heavy():
        with httpx.Client(base_url=url, timeout=120) as c:
            while not stop.is_set():
                code = c.post("/v1/bsdf/eval", json=HEAVY_EVAL).status_code
                with lock:
                    codes[str(code) if code in (200, 429) else "other"] += 1

    workers = [threading.Thread(target=heavy) for _ in range(2 * heavy_slots)]
    for w in workers:
        w.start()
    latencies, start = [], time.perf_counter()
    while time.perf_counter() - start < seconds:
        t = time.perf_counter()
        client.get("/healthz").raise_for_status()
        latencies.append(time.perf_counter() - t)
        time.sleep(0.01)
    wall = time.perf_counter() - start
    stop.set()
    for w in workers:
        w.join()
    return {"saturated": {**stats(latencies, wall), "heavy_ok_per_s": codes["200"] / wall, **codes}}


# -- the direct calls (this process) ----------------------------------------------------------
def direct(requests: int) -> dict:
    from bsdflab import from_dict
    from bsdflab.slices import evaluate

    wi, wo = directions()
    out = {}
    for name, m in MODELS.items():
        bsdf = from_dict(m)
        evaluate(bsdf, wi, wo)
        latencies = []
        start = time.perf_counter()
        for _ in range(requests):
            t = time.perf_counter()
            evaluate(bsdf, wi, wo)
            latencies.append(time.perf_counter() - t)
        out[f"eval/{name}"] = stats(latencies, time.perf_counter() - start)
    return out


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--requests", type=int, default=200, help="requests per scenario (default 200)")
    p.add_argument("--concurrency", type=int, default=4, help="connections in flight (default 4)")
    p.add_argument("--seconds", type=float, default=20.0, help="time cap per scenario (default 20)")
    p.add_argument("--load", metavar="URL", help=argparse.SUPPRESS)   # the load-generator process
    p.add_argument("--heavy", type=int, default=None, help=argparse.SUPPRESS)
    args = p.parse_args()
    heavy = args.heavy or args.concurrency   # the server's heavy pool: the eval scenarios' clients all fit
    if args.load:
        print(json.dumps(load(args.load, args.requests, args.concurrency, args.seconds, heavy)))
        return 0

    sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
    from support.service_process import ServiceProcess

    with tempfile.TemporaryDirectory() as data:
        server = ServiceProcess(Path(data), workers=1, env={"BSDFLAB_HEAVY_CONCURRENCY": str(heavy),
                                                            "BSDFLAB_COMPUTE_DEADLINE_S": "60"})
        try:
            http = {c: json.loads(subprocess.run(
                [sys.executable, __file__, "--load", server.url, "--requests", str(args.requests),
                 "--concurrency", str(c), "--seconds", str(args.seconds), "--heavy", str(heavy)],
                capture_output=True, text=True, check=True).stdout) for c in (1, args.concurrency)}
        finally:
            server.stop()
    here = direct(args.requests)
    print(f"load: {os.getloadavg()[0]:.1f} (1-min average; the machine is shared), {os.cpu_count()} cores, "
          f"{PAIRS} pairs per eval")
    print(f"{'scenario':<16} {'path':<18} {'req/s':>9} {'p50 ms':>9} {'p99 ms':>9}")
    for c, results in http.items():
        for name, s in results.items():
            print(f"{name:<16} {f'http, {c} in flight':<18} {s['per_s']:9.1f} {s['p50_ms']:9.2f} {s['p99_ms']:9.2f}")
    one = http[1]
    print(f"100 000 pairs: JSON {one['big/json']['bytes'] / 2**20:.1f} MiB, .npy {one['big/npy']['bytes'] / 2**20:.1f} "
          f"MiB; p50 JSON / .npy = {one['big/json']['p50_ms'] / one['big/npy']['p50_ms']:.2f}")
    sat = one["saturated"]
    print(f"saturated ({2 * heavy} clients on {heavy} heavy slots): /healthz p99 {sat['p99_ms']:.2f} ms = "
          f"{sat['p99_ms'] / one['healthz']['p99_ms']:.2f} x idle; heavy evals {sat['heavy_ok_per_s']:.2f}/s "
          f"at the cap, "
          f"{sat['429']} answered 429, {sat['200']} 200, {sat['other']} other")
    for name, s in here.items():
        print(f"{name:<16} {'direct':<18} {s['per_s']:9.1f} {s['p50_ms']:9.2f} {s['p99_ms']:9.2f}")
    print("ratios, one request in flight (p50 latency):")
    for name in here:
        ratio = http[1][name]["p50_ms"] / here[name]["p50_ms"]
        print(f"  {name}: http / direct = {ratio:.2f} (goal < 2: {'met' if ratio < 2 else 'not met'}); "
              f"http / healthz = {http[1][name]['p50_ms'] / http[1]['healthz']['p50_ms']:.2f}")
    print(f"throughput with {args.concurrency} in flight / direct sequential:")
    for name in here:
        print(f"  {name}: {http[args.concurrency][name]['per_s'] / here[name]['per_s']:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
