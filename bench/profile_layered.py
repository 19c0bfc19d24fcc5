"""The layered walk's cost for profilers and refactors (bench/README.md, "Profiling the layered walk").

Workloads, CPU-microseconds per walk (steadier than wall time on a loaded machine):
  snake eval      the xenopeltis preset through 81 wavelengths, 16 direction pairs x `--walks`
                  walks, with the chosen estimator (eval's walk, core/src/layered/eval_walk.cpp);
  bright eval     a thick bright slab (tau 10, albedo 0.99) under a rough top (pfmc2's
                  smallest-extinction flights);
  delta eval      a smooth three-boundary stack over silver (the delta region's connections);
  snake sample    sample() of the preset, with the pdf() it reports (sample()'s walk,
                  core/src/layered/sample_walk.cpp), per sample.
One thread gives the cleanest profile: BSDFLAB_THREADS=1.

With --baseline-core PATH (a _core .so built from an earlier commit, bench/build_core_at.sh),
the same workloads run alternately in child processes on this build's core and on the
baseline's, `--rounds` times each, and the script prints the median of each side and the
ratio baseline / this (> 1: this build is faster), also of the fastest rounds (the least
disturbed by other processes on a shared machine).

    python bench/profile_layered.py [--estimator pfmc2] [--walks 4000]
    python bench/profile_layered.py --baseline-core /tmp/core-main.so [--rounds 5]
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import statistics
import subprocess
import sys
import time


def _load_core(path: str) -> None:
    """Import bsdflab with the compiled core at `path` (an earlier build) instead of its own."""
    spec = importlib.util.spec_from_file_location("bsdflab._core", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules["bsdflab._core"] = module
    spec.loader.exec_module(module)


def _models(estimator: str):
    """name -> (Layered model, wavelengths)."""
    import numpy as np

    import bsdflab as bl
    from bsdflab.spectra import DEFAULT_WAVELENGTHS

    wl = np.asarray(DEFAULT_WAVELENGTHS, dtype=float)
    snake = bl.presets.xenopeltis()
    bright = bl.Slab(1.0, sigma_a=0.1, sigma_s=9.9, phase={"type": "hg", "g": 0.6})
    return {
        "snake": (bl.Layered(list(snake.interfaces), list(snake.slabs), snake.base, estimator=estimator), wl),
        "bright": (
            bl.Layered([bl.RoughDielectric(0.3, 1.5, 1.0)], [bright], bl.Diffuse(0.9), estimator=estimator),
            [450.0, 550.0, 650.0],
        ),
        "delta": (
            bl.Layered(
                [bl.Dielectric(1.5, 1.0), bl.Dielectric(1.3, 1.5), bl.Dielectric(1.4, 1.3)],
                [bl.Slab(0.4, sigma_a=0.1), bl.Slab(0.3, sigma_a=0.05, sigma_s=0.8), bl.Slab(0.5, sigma_a=0.2)],
                bl.Conductor(material="Ag", ext_ior=1.4),
                estimator=estimator,
            ),
            [450.0, 550.0, 650.0],
        ),
    }


def measure(estimator: str, walks: int) -> dict[str, float]:
    """CPU-microseconds per walk of each workload on the imported core."""
    import numpy as np

    import bsdflab as bl
    from bsdflab.testing import random_unit_vectors

    wi = random_unit_vectors(16, seed=11, hemisphere="upper")
    wo = random_unit_vectors(16, seed=12, hemisphere="upper")
    out = {}
    for name, (model, wl) in _models(estimator).items():
        core = model._core(np.asarray(wl, dtype=float))
        cpu0 = time.process_time()
        core.estimate(wi, wo, int(bl.Lobe.ALL), None, walks, 7)
        out[f"{name} eval"] = 1e6 * (time.process_time() - cpu0) / (16 * walks)
    model, wl = _models(estimator)["snake"]
    n = 4 * walks
    rng = np.random.default_rng(5)
    ws = random_unit_vectors(n, seed=13, hemisphere="upper")
    cpu0 = time.process_time()
    model.sample(ws, rng.random(n), rng.random((n, 2)), wavelengths=wl)
    out["snake sample"] = 1e6 * (time.process_time() - cpu0) / n
    return out


def _worker(core: str | None, estimator: str, walks: int) -> dict[str, float]:
    cmd = [sys.executable, os.path.abspath(__file__), "--worker", "--estimator", estimator, "--walks", str(walks)]
    if core:
        cmd += ["--core", core]
    done = subprocess.run(cmd, check=True, capture_output=True, text=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def compare(baseline: str, estimator: str, walks: int, rounds: int) -> None:
    this, base = [], []
    for _ in range(rounds):  # alternate, so that a change of machine load hits both sides
        this.append(_worker(None, estimator, walks))
        base.append(_worker(baseline, estimator, walks))
    print(f"estimator {estimator}, {walks} walks, {rounds} rounds: CPU-us per walk, median (and fastest) round")
    print(f"{'workload':14s} {'this':>9s} {'baseline':>9s} {'baseline/this':>14s} {'fastest: ratio':>15s}")
    for key in this[0]:
        a = statistics.median(r[key] for r in this)
        b = statistics.median(r[key] for r in base)
        fast = min(r[key] for r in base) / min(r[key] for r in this)
        print(f"{key:14s} {a:9.2f} {b:9.2f} {b / a:14.3f} {fast:15.3f}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--estimator", default="pfmc2", choices=("pfmc", "pfmc2"))
    ap.add_argument("--walks", type=int, default=4000)
    ap.add_argument("--baseline-core", default=None, help="a _core .so of an earlier build to compare against")
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--core", default=None, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker:
        print(json.dumps(measure(args.estimator, args.walks)))
    elif args.baseline_core:
        compare(os.path.abspath(args.baseline_core), args.estimator, args.walks, args.rounds)
    else:
        for key, us in measure(args.estimator, args.walks).items():
            print(f"{args.estimator} {key}: {us:.2f} CPU-us per walk")


if __name__ == "__main__" and "--core" in sys.argv:  # before bsdflab imports its own core
    _load_core(sys.argv[sys.argv.index("--core") + 1])

if __name__ == "__main__":
    main()
