"""The adding-doubling solver's CPU time on this tree's core against an earlier build of
it, in the same run: after a refactor of core/src/adding_doubling*.cpp, "no slower" is a
ratio measured here, never a number from another day (docs/solvers.md, "Code layout").

    bench/build_core_at.sh main /tmp/core-main.so
    BSDFLAB_THREADS=1 python bench/bench_solver_core.py --baseline-core /tmp/core-main.so

Each round runs both cores, alternating which goes first, each in its own child process
(the baseline's loaded before bsdflab imports its own), timing a fresh solve plus eval of
a smooth-top stack, a rough-top stack (the snake) and a two-sided stack, 3 wavelengths, in
process CPU time. Prints per stack the median over rounds of (this core / baseline) and
both medians; with BSDFLAB_THREADS=1 CPU time is the work (no thread pool spinning).
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import subprocess
import sys
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
from bsdflab.solvers import solve  # noqa: E402
from bsdflab.testing import random_unit_vectors  # noqa: E402

WL = [450.0, 550.0, 650.0]
HG = bl.Slab(2.0, sigma_a=0.1, sigma_s=0.5, phase={"type": "hg", "g": 0.6})
STACKS = {
    "smooth 1.5 / HG 0.6 / Lambertian": lambda: bl.Layered([bl.Dielectric(1.5, 1.0)], [HG], bl.Diffuse(0.5)),
    "xenopeltis (rough film top)": lambda: bl.presets.preset("xenopeltis"),
    "two-sided smooth / HG / water": lambda: bl.Layered([bl.Dielectric(1.5, 1.0)], [HG], bl.Dielectric(1.33, 1.5)),
}


def worker(pairs: int) -> dict:
    """CPU seconds of solve + eval per stack (both signs of z for the two-sided one)."""
    wi = random_unit_vectors(pairs, seed=1, hemisphere="upper")
    wo = random_unit_vectors(pairs, seed=2, hemisphere="upper")
    out = {}
    for name, make in STACKS.items():
        model = make()
        t0 = time.process_time()
        sol = solve(model, WL)
        sol.eval(wi, wo)
        if sol.two_sided:
            sol.eval(wi * [1.0, 1.0, -1.0], wo)
        out[name] = time.process_time() - t0
    return out


def child(core: str | None, pairs: int) -> dict:
    cmd = [sys.executable, os.path.abspath(__file__), "--worker", "--pairs", str(pairs)]
    cmd += ["--core", core] if core else []
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--baseline-core", help="an earlier build of bsdflab/_core*.so (bench/build_core_at.sh)")
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--pairs", type=int, default=64)
    ap.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--core", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker:
        print(json.dumps(worker(args.pairs)))
        return
    if not args.baseline_core:
        ap.error("--baseline-core PATH is required (build it with bench/build_core_at.sh)")
    mine, base = [], []
    for r in range(args.rounds):
        order = [(None, mine), (args.baseline_core, base)]
        for core, sink in order if r % 2 == 0 else order[::-1]:
            sink.append(child(core, args.pairs))
    print(
        f"adding-doubling solve + eval, CPU-s, median of {args.rounds} rounds "
        f"(load average {os.getloadavg()[0]:.1f}, BSDFLAB_THREADS={os.environ.get('BSDFLAB_THREADS', 'all')})"
    )
    print(f"  {'stack':36s} {'this core':>10s} {'baseline':>10s} {'ratio':>7s}")
    for name in STACKS:
        a, b = np.array([m[name] for m in mine]), np.array([x[name] for x in base])
        print(f"  {name:36s} {np.median(a):10.3f} {np.median(b):10.3f} {np.median(a / b):7.3f}")


if __name__ == "__main__":
    main()
