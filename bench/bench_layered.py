"""PFMC layered BSDF: cost of a 1 % estimate, and NEE+MIS efficiency vs a naive walk.

For the xenopeltis preset (RGB output, 81 wavelengths per walk) over a set of direction
pairs, measures in one run, on every core:
  * walks/s of the full estimator (next-event connections + MIS) and of the naive walk
    (no connections: a walk contributes only when it scatters toward the rough top and the
    top's BTDF is evaluated toward wo),
  * the relative variance per walk of each (from the estimator's own standard error),
  * efficiency = 1 / (variance x time), and the ratio NEE+MIS / naive,
  * the time per direction pair to reach 1 % relative standard error.
  * with --per-walk: ns per walk of small estimates (1 and 8 wavelengths, the xenopeltis
    preset and a plastic stack), where per-walk overheads such as allocations show.
  * with --allocations (under LD_PRELOAD of bench/malloc_count.c, see there): heap
    allocations per walk and per eval() call, counted, not timed.
Run: python3 bench/bench_layered.py [--pairs 32] [--samples 2000] [--per-walk] [--allocations]
     python3 bench/bench_layered.py --compare [...]   the estimators side by side, against a
         baseline core: bench/bench_layered_compare.py with the arguments that follow
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

import bsdflab as bl
from bsdflab import _core
from bsdflab.spectra import DEFAULT_WAVELENGTHS, srgb_weights
from bsdflab.tables.channels import LUMINANCE_RGB
from bsdflab.testing import random_unit_vectors


def luminance_rel_variance(value, err, wl):
    """Per-walk relative variance of the luminance (Y) estimate, one per pair."""
    W = srgb_weights(wl)
    y = LUMINANCE_RGB @ W                                 # spectrum -> luminance weights
    mean = value @ y
    se = err @ np.abs(y)                                  # correlated channels: upper bound
    return mean, se


def run(core, wi, wo, samples, seed=1):
    t0 = time.perf_counter()
    value, err, nonfinite, _ = core.estimate(wi, wo, int(bl.Lobe.ALL), None, samples, seed)
    assert nonfinite == 0, f"{nonfinite} non-finite walks"
    return value, err, time.perf_counter() - t0


def main() -> None:
    if "--compare" in sys.argv[1:]:  # the name for the side-by-side benchmark
        import runpy
        sys.argv = [str(Path(__file__).with_name("bench_layered_compare.py"))] + [
            a for a in sys.argv[1:] if a != "--compare"]
        runpy.run_path(sys.argv[0], run_name="__main__")
        return
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--pairs", type=int, default=32)
    ap.add_argument("--samples", type=int, default=2000)
    ap.add_argument("--per-walk", action="store_true", help="also time small per-walk estimates")
    ap.add_argument("--allocations", action="store_true", help="count heap allocations (LD_PRELOAD)")
    args = ap.parse_args()
    if args.allocations:
        allocations()
    if args.per_walk:
        per_walk()

    model = bl.presets.xenopeltis()
    wl = DEFAULT_WAVELENGTHS
    full = model._core(wl)
    naive = model.naive(wl)
    wi = random_unit_vectors(args.pairs, seed=1, hemisphere="upper")
    wo = random_unit_vectors(args.pairs, seed=2, hemisphere="upper")
    run(full, wi[:2], wo[:2], 16)  # warm up (thread start, caches)

    print(f"xenopeltis preset, {args.pairs} direction pairs, {args.samples} walks each, "
          f"{len(wl)} wavelengths, {_core.worker_count()} threads")
    rows = {}
    for name, core in (("NEE+MIS", full), ("naive", naive)):
        value, err, dt = run(core, wi, wo, args.samples)
        mean, se = luminance_rel_variance(value, err, wl)
        ok = mean > 0
        rel_var_per_walk = (se[ok] / mean[ok]) ** 2 * args.samples   # variance of one walk / mean^2
        t_walk = dt / (args.pairs * args.samples)
        # walks needed for 1 % relative standard error, and the time for them per pair
        walks_1pct = rel_var_per_walk / 1e-4
        rows[name] = dict(t_walk=t_walk, var=np.median(rel_var_per_walk),
                          t_1pct=np.median(walks_1pct) * t_walk,
                          eff=1.0 / (np.median(rel_var_per_walk) * t_walk))
        r = rows[name]
        print(f"  {name:8s} {1e6 * t_walk:7.2f} us/walk   rel. variance/walk {r['var']:9.3g}   "
              f"time to 1 % per pair {1e3 * r['t_1pct']:8.2f} ms   efficiency {r['eff']:9.3g} /s")
    print(f"efficiency ratio NEE+MIS / naive: {rows['NEE+MIS']['eff'] / rows['naive']['eff']:.1f}x")


def per_walk() -> None:
    """ns per walk for few channels: the per-walk overheads (allocation, set-up) show here."""
    wi = random_unit_vectors(64, seed=1, hemisphere="upper")
    wo = random_unit_vectors(64, seed=2, hemisphere="upper")
    plastic = bl.Layered([bl.Dielectric(1.5)], [bl.Slab(0.0)], bl.Diffuse(0.5))
    for name, model in (("xenopeltis", bl.presets.xenopeltis()), ("plastic", plastic)):
        for wl in ([550.0], list(np.linspace(400, 700, 8))):
            model.eval_with_error(wi[:2], wo[:2], wavelengths=wl, samples=100)
            best = min(_timed(model, wi, wo, wl) for _ in range(3))
            print(f"  {name:11s} {len(wl)} wavelengths: {1e9 * best / (64 * 4000):8.1f} ns/walk")


def allocations() -> None:
    """Heap allocations per walk (from the difference of two efforts) and per plain eval()."""
    import ctypes
    import os

    lib = next((p for p in os.environ.get("LD_PRELOAD", "").split(":") if "malloc_count" in p), None)
    if lib is None:
        raise SystemExit("--allocations needs LD_PRELOAD=<malloc_count.so> (see bench/malloc_count.c)")
    count = ctypes.CDLL(lib).malloc_count
    count.restype = ctypes.c_long
    threads = os.environ.get("BSDFLAB_THREADS")
    os.environ["BSDFLAB_THREADS"] = "1"  # one thread: no thread start-up allocations
    wi = random_unit_vectors(16, seed=1, hemisphere="upper")
    wo = random_unit_vectors(16, seed=2, hemisphere="upper")
    plastic = bl.Layered([bl.Dielectric(1.5)], [bl.Slab(0.0)], bl.Diffuse(0.5))
    for name, model in (("xenopeltis", bl.presets.xenopeltis()), ("plastic", plastic)):
        core = model._core(np.array([550.0]))
        model.eval_with_error(wi, wo, wavelengths=[550.0], samples=10)
        used = []
        for n in (100, 1100):
            c0 = count()
            model.eval_with_error(wi, wo, wavelengths=[550.0], samples=n)
            used.append(count() - c0)
        c0 = count()
        core.eval(wi, wo, int(bl.Lobe.ALL), None)
        per_eval = count() - c0
        print(f"  {name:11s} {(used[1] - used[0]) / (1000 * 16):.3f} allocations per walk; "
              f"{per_eval} per eval() call of 16 pairs x {model.samples} walks")
    if threads is None:
        del os.environ["BSDFLAB_THREADS"]
    else:
        os.environ["BSDFLAB_THREADS"] = threads


def _timed(model, wi, wo, wl) -> float:
    t = time.perf_counter()
    model.eval_with_error(wi, wo, wavelengths=wl, samples=4000)
    return time.perf_counter() - t


if __name__ == "__main__":
    main()
