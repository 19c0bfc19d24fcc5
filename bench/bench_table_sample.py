"""A layered table's sample() per call on this tree's core against an earlier build of it,
in the same run, and whether both return the same bits (docs/known_limits.md, the delta
lobes' cost).

    bench/build_core_at.sh <commit> /tmp/core-base.so
    BSDFLAB_THREADS=1 python bench/bench_table_sample.py --baseline-core /tmp/core-base.so

The tables are adding-doubling ones (RGB, 4 x 8 x 5), made once by this tree and read by
both cores: a filmed top over gold (its delta lobes: a 1-D adding over 81 wavelengths per
solve, core/include/bsdflab/table_delta.h) and a two-sided glass-over-water stack
(spectrally flat: one channel, light from above and below). Each round runs both cores,
alternating which goes first, each in its own child process (the baseline's core loaded
before bsdflab imports its own), timing sample(), pdf() and eval() over the same incident
directions in process CPU time. Prints per table the median per-call microseconds of each
core and their ratio, and a SHA-256 of every returned array per core: equal digests are
bit-identical answers.
"""

from __future__ import annotations

import argparse
import hashlib
import importlib.util
import json
import os
import subprocess
import sys
import tempfile
import time


def _load_core(path: str) -> None:
    """Import bsdflab with the compiled core at `path` (an earlier build) instead of its own."""
    spec = importlib.util.spec_from_file_location("bsdflab._core", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules["bsdflab._core"] = module
    spec.loader.exec_module(module)


if __name__ == "__main__" and "--core" in sys.argv:  # before bsdflab imports its own core
    _load_core(sys.argv[sys.argv.index("--core") + 1])

import numpy as np  # noqa: E402

import bsdflab as bl  # noqa: E402

FILM = [{"material": 1.38, "thickness_nm": 300.0}]
MODELS = {
    "filmed top over gold": lambda: bl.Layered([bl.Dielectric(1.5, 1.0, film=FILM)],
                                               [bl.Slab(1.0, sigma_a=0.1, sigma_s=1.0)],
                                               bl.Conductor("Au", ext_ior=1.5)),
    "glass over water (two-sided)": lambda: bl.Layered([bl.Dielectric(1.5, 1.0)],
                                                       [bl.Slab(1.0, sigma_a=0.1, sigma_s=1.0)],
                                                       bl.Dielectric(1.33, 1.5)),
}
GRID = (4, 8, 5)


def make_tables(folder: str) -> dict:
    from bsdflab.tables import TableGrid, tabulate, write_table

    paths = {}
    for i, (name, make) in enumerate(MODELS.items()):
        table = tabulate(make(), TableGrid(*GRID), rel_error=0.01, method="adding-doubling", progress=False)
        paths[name] = os.path.join(folder, f"table{i}.exr")
        write_table(paths[name], table)
    return paths


def directions(n: int, two_sided: bool, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    mu, phi = rng.uniform(0.05, 1.0, n), rng.uniform(0, 2 * np.pi, n)
    if two_sided:
        mu = np.where(rng.random(n) < 0.5, mu, -mu)
    s = np.sqrt(1 - mu**2)
    return np.stack([s * np.cos(phi), s * np.sin(phi), mu], axis=-1)


def worker(paths: dict, n: int) -> dict:
    """Per table: CPU microseconds per call of sample, pdf, eval, and a digest of their output."""
    from bsdflab.tables import TableBSDF, read_table

    out = {}
    for name, path in paths.items():
        tb = TableBSDF(read_table(path))
        wi = directions(n, tb.table.two_sided, seed=1)
        tb.sample(wi[:16], seed=0)  # build the core outside the timing
        t0 = time.process_time()
        s = tb.sample(wi, seed=2)
        t1 = time.process_time()
        p = tb.pdf(wi, s.wo)
        t2 = time.process_time()
        f = tb.eval(wi, s.wo)
        t3 = time.process_time()
        digest = hashlib.sha256()
        for a in (s.wo, s.weight, s.pdf, s.lobe, s.eta, p, f):
            digest.update(np.ascontiguousarray(a).tobytes())
        out[name] = {"sample": (t1 - t0) / n * 1e6, "pdf": (t2 - t1) / n * 1e6, "eval": (t3 - t2) / n * 1e6,
                     "digest": digest.hexdigest()}
    return out


def child(core: str | None, paths: dict, n: int) -> dict:
    cmd = [sys.executable, os.path.abspath(__file__), "--worker", json.dumps(paths), "--calls", str(n)]
    cmd += ["--core", core] if core else []
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--baseline-core", help="an earlier build of bsdflab/_core*.so (bench/build_core_at.sh)")
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--calls", type=int, default=20_000, help="incident directions per timed call")
    ap.add_argument("--worker", help=argparse.SUPPRESS)
    ap.add_argument("--core", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker:
        print(json.dumps(worker(json.loads(args.worker), args.calls)))
        return
    if not args.baseline_core:
        ap.error("--baseline-core PATH is required (build it with bench/build_core_at.sh)")
    with tempfile.TemporaryDirectory() as folder:
        paths = make_tables(folder)
        mine, base = [], []
        for r in range(args.rounds):
            order = [(None, mine), (args.baseline_core, base)]
            for core, sink in order if r % 2 == 0 else order[::-1]:
                sink.append(child(core, paths, args.calls))
    print(f"table sample/pdf/eval, CPU microseconds per call, median of {args.rounds} rounds x {args.calls} calls "
          f"(load average {os.getloadavg()[0]:.1f}, BSDFLAB_THREADS={os.environ.get('BSDFLAB_THREADS', 'all')})")
    print(f"  {'table':30s} {'call':7s} {'this core':>10s} {'baseline':>10s} {'ratio':>7s}")
    for name in MODELS:
        for call in ("sample", "pdf", "eval"):
            a, b = np.array([m[name][call] for m in mine]), np.array([x[name][call] for x in base])
            print(f"  {name:30s} {call:7s} {np.median(a):10.2f} {np.median(b):10.2f} {np.median(a / b):7.3f}")
        digests = {m[name]["digest"] for m in mine} | {x[name]["digest"] for x in base}
        print(f"  {name:30s} outputs bit-identical across cores and rounds: {len(digests) == 1} "
              f"(sha256 {sorted(digests)[0][:16]})")


if __name__ == "__main__":
    main()
