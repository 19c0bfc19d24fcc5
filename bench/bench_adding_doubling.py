"""Adding-doubling vs PFMC: the snake table's time and error, ratios in one run.

(a) snake table (the render's first-use grid: 8 x 16 x 9 x 3 thickness nodes, RGB) by
    PFMC at 2 % (film lookup, as bsdflab.scenes.snake tabulates it) and by adding-doubling
    (16 nodes): wall and CPU seconds, and each table's error against a reference
    adding-doubling table (32 nodes), max and RMS over the significant cells;
(b) per-direction-pair cost of one eval at 1 % and at 1e-4 (solver bound) vs PFMC walks.

    python bench/bench_adding_doubling.py [--quick]
"""
from __future__ import annotations

import argparse
import os
import time

import numpy as np

from bsdflab.presets import preset
from bsdflab.scenes.snake import table_grid
from bsdflab.tables import TableGrid, tabulate
from bsdflab.tables.adding_doubling import tabulate_adding_doubling
from bsdflab.tables.channels import LUMINANCE_RGB


def timed(fn):
    w, c = time.perf_counter(), time.process_time()
    out = fn()
    return out, time.perf_counter() - w, time.process_time() - c


def errors(table, ref):
    lum, lum_ref = table.values @ LUMINANCE_RGB, ref.values @ LUMINANCE_RGB
    mask = lum_ref > 0.01 * lum_ref.max()
    rel = np.abs(lum[mask] - lum_ref[mask]) / lum_ref[mask]
    return float(rel.max()), float(np.sqrt(np.mean(rel**2)))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="a 4 x 6 x 5 x 1 grid instead of the snake's")
    args = ap.parse_args()
    model = preset("xenopeltis")
    grid = TableGrid(4, 6, 5) if args.quick else TableGrid.from_dict(table_grid())
    print(f"grid {grid.n_theta_i} x {grid.n_theta_o} x {grid.n_phi} x {max(1, len(grid.thickness_nm))} "
          f"thickness nodes, RGB, load {os.getloadavg()[0]:.1f}")
    ref, w_ref, c_ref = timed(lambda: tabulate_adding_doubling(model, grid, nodes=24))
    ad, w_ad, c_ad = timed(lambda: tabulate(model, grid, method="adding-doubling", progress=False))
    mc, w_mc, c_mc = timed(lambda: tabulate(model, grid, rel_error=0.02, progress=False))
    e_ad, e_mc = errors(ad, ref), errors(mc, ref)
    print(f"(a) reference AD (24 nodes): {w_ref:.1f} s wall, {c_ref:.1f} CPU-s")
    print(f"    PFMC 2 %:  {w_mc:.1f} s wall, {c_mc:.1f} CPU-s; error vs reference max {e_mc[0]:.4f}, "
          f"RMS {e_mc[1]:.4f}")
    print(f"    AD 16 nodes: {w_ad:.1f} s wall, {c_ad:.1f} CPU-s; error vs reference max {e_ad[0]:.2e}, "
          f"RMS {e_ad[1]:.2e}; stated bound max {ad.meta['error_bound_max_rel']:.2e}")
    print(f"    ratio PFMC / AD: wall {w_mc / w_ad:.1f}x, CPU {c_mc / c_ad:.1f}x, max error {e_mc[0] / e_ad[0]:.0f}x")


if __name__ == "__main__":
    main()
