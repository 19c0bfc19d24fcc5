"""BSDF tables: tabulation time and accuracy, parallel efficiency, and table vs PFMC speed.

For the xenopeltis preset (RGB tables, 81 wavelengths per walk), in one run:
  (a) the time to tabulate it to a target relative error, with the achieved error
      (RMS / 95th percentile / max relative standard error of the luminance over the
      cells above 1 % of the maximum) and the walk rate;
  (b) parallel efficiency 1 -> 2 threads: the same small tabulation in two subprocesses
      with BSDFLAB_THREADS=1 and =2 (tabulation time only, as the job measures it, so
      interpreter start-up is not counted); the two tables must be identical;
  (c) queries/s of the table from (a) -- eval, pdf, sample -- against direct PFMC
      (xenopeltis, samples=256): eval and sample, and their ratios;
  (d) the snake's table at first use (bsdflab.scenes.snake.tabulated: 8 x 16 x 9 x 3
      thickness nodes, 2 %, min_samples 512), old vs new in this run: film_lookup=False
      (every film crossing by the exact Airy sums: the walks and values of estimator
      version 3, bit for bit) against the default film lookup (version 4), with wall and
      CPU seconds, walks, and the achieved RMS / 95th percentile relative error of both
      (~3 minutes at load 0 on 2 cores; --no-snake skips it).
The README figure (default grid 12 x 24 x 13, 1 %) takes ~6-7 minutes on 2 cores:
    python bench/bench_tables.py --grid default --rel-error 0.01
The defaults are a quick run (~1 minute): --grid small (6 x 12 x 7) --rel-error 0.02.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time

import numpy as np

GRIDS = {"small": (6, 12, 7), "default": (12, 24, 13)}
PARALLEL_GRID = (4, 8, 5)       # (b): a few seconds on one thread
PARALLEL_REL_ERROR = 0.03


def tabulate_preset(grid, rel_error, seed=0):
    import bsdflab as bl
    from bsdflab.tables import TableGrid, tabulate

    return tabulate(bl.presets.xenopeltis(), TableGrid(*grid), rel_error=rel_error, seed=seed,
                    progress=False)


def worker(grid, rel_error) -> None:
    """(b), in a subprocess: tabulate and print the job's own timing and a table digest."""
    import hashlib

    from bsdflab import _core

    table = tabulate_preset(grid, rel_error)
    digest = hashlib.sha256(table.values.tobytes() + table.samples.tobytes()).hexdigest()
    print(json.dumps({"seconds": table.meta["seconds"], "threads": _core.worker_count(),
                      "walks": int(table.samples.sum()), "digest": digest}))


def run_worker(threads: int, grid, rel_error) -> dict:
    env = dict(os.environ, BSDFLAB_THREADS=str(threads))
    out = subprocess.run([sys.executable, __file__, "--worker", json.dumps([list(grid), rel_error])],
                         env=env, capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def rate(fn, n: int, repeat: int = 3) -> float:
    """Queries per second: the best of `repeat` timed calls on n queries."""
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return n / best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--grid", choices=sorted(GRIDS), default="small",
                    help="small = 6 x 12 x 7 (default), default = TableGrid() 12 x 24 x 13")
    ap.add_argument("--rel-error", type=float, default=0.02, help="target relative error (default 0.02)")
    ap.add_argument("--queries", type=int, default=200_000, help="table queries for (c)")
    ap.add_argument("--pfmc-queries", type=int, default=1000, help="PFMC queries for (c)")
    ap.add_argument("--no-snake", action="store_true", help="skip (d), the snake table old vs new")
    ap.add_argument("--only-snake", action="store_true", help="run (d) only")
    ap.add_argument("--worker", default=None, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker is not None:
        grid, rel_error = json.loads(args.worker)
        worker(tuple(grid), rel_error)
        return

    import bsdflab as bl
    from bsdflab import _core
    from bsdflab.tables import TableBSDF
    from bsdflab.testing import random_unit_vectors

    threads = _core.worker_count()
    if args.only_snake:
        snake_old_vs_new(threads)
        return
    grid = GRIDS[args.grid]
    cells = int(np.prod(grid))
    print(f"xenopeltis preset, RGB tables (81 wavelengths per walk), {threads} threads")

    # (a) tabulation to a target error
    table = tabulate_preset(grid, args.rel_error)
    m = table.meta
    walks = int(table.samples.sum())
    print(f"(a) tabulate {args.grid} grid {' x '.join(map(str, grid))} ({cells} cells), "
          f"target {args.rel_error:g}: {m['seconds']:.1f} s; achieved rel. error RMS "
          f"{m['rel_error_rms']:.4f}, 95 % {m['rel_error_p95']:.4f}, max {m['rel_error_max']:.4f}; "
          f"{walks:,} walks ({walks / cells:.0f} per cell, {walks / m['seconds'] / 1e3:.1f} k walks/s)")

    # (b) parallel efficiency 1 -> 2 threads
    one = run_worker(1, PARALLEL_GRID, PARALLEL_REL_ERROR)
    two = run_worker(2, PARALLEL_GRID, PARALLEL_REL_ERROR)
    speedup = one["seconds"] / two["seconds"]
    same = "identical tables" if one["digest"] == two["digest"] else "TABLES DIFFER"
    print(f"(b) grid {' x '.join(map(str, PARALLEL_GRID))}, target {PARALLEL_REL_ERROR:g} "
          f"({one['walks']:,} walks): 1 thread {one['seconds']:.2f} s, 2 threads "
          f"{two['seconds']:.2f} s -> speed-up {speedup:.2f}x, efficiency {speedup / 2:.0%} ({same})")

    # (c) queries/s: the table vs direct PFMC, same directions, all threads
    model = bl.presets.xenopeltis(samples=256)
    tb = TableBSDF(table)
    n, k = args.queries, args.pfmc_queries
    wi = random_unit_vectors(n, seed=1, hemisphere="upper")
    wo = random_unit_vectors(n, seed=2, hemisphere="upper")
    tb.eval(wi[:10], wo[:10]), model.eval(wi[:2], wo[:2])  # build the cores outside the timing
    r = {"table eval": rate(lambda: tb.eval(wi, wo), n),
         "table pdf": rate(lambda: tb.pdf(wi, wo), n),
         "table sample": rate(lambda: tb.sample(wi, seed=3), n),
         "PFMC eval (256 walks)": rate(lambda: model.eval(wi[:k], wo[:k]), k, repeat=1),
         "PFMC sample": rate(lambda: model.sample(wi[:n // 10], seed=3), n // 10, repeat=1)}
    print("(c) queries/s: " + ", ".join(f"{name} {v:,.0f}" for name, v in r.items()))
    print(f"    table eval / PFMC eval {r['table eval'] / r['PFMC eval (256 walks)']:,.0f}x, "
          f"table sample / PFMC sample {r['table sample'] / r['PFMC sample']:,.1f}x, "
          f"table sample / PFMC eval {r['table sample'] / r['PFMC eval (256 walks)']:,.0f}x")
    if not args.no_snake:
        snake_old_vs_new(threads)


def snake_old_vs_new(threads: int) -> None:
    """(d): the snake's first-use table, exact film (old) then film lookup (new)."""
    import bsdflab as bl
    from bsdflab.scenes.snake import tabulated
    from bsdflab.tables import TableGrid, tabulate

    spec = tabulated(bl.presets.xenopeltis().to_dict())
    grid = TableGrid.from_dict(spec["grid"])
    runs = {}
    for name, lookup in (("old (exact film)", False), ("new (film lookup)", True)):
        load = os.getloadavg()[0]
        cpu0, wall0 = time.process_time(), time.perf_counter()
        table = tabulate(bl.presets.xenopeltis(), grid, rel_error=spec["rel_error"], progress=False,
                         film_lookup=lookup)
        wall, cpu = time.perf_counter() - wall0, time.process_time() - cpu0
        m = table.meta
        walks = int(table.samples.sum()) + m["pilot_walks"]
        runs[name] = (wall, cpu)
        print(f"(d) snake table {name}: {wall:.1f} s wall, {cpu:.1f} CPU-s ({threads} threads, load {load:.1f} "
              f"at start); {walks:,} walks ({cpu / walks * 1e6:.1f} CPU-us per walk); rel. error RMS "
              f"{m['rel_error_rms']:.4f}, 95 % {m['rel_error_p95']:.4f}, max {m['rel_error_max']:.4f}; "
              f"film lookup error {m['film_lookup_error']}")
    (w0, c0), (w1, c1) = runs.values()
    print(f"    new / old: wall {w1 / w0:.2f}x, CPU {c1 / c0:.2f}x (speed-up {w0 / w1:.2f}x wall, {c0 / c1:.2f}x CPU)")


if __name__ == "__main__":
    main()
