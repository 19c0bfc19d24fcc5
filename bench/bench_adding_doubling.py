"""Adding-doubling vs PFMC: the snake table's time and error, ratios in one run.

(a) snake table (the render's first-use grid: 8 x 16 x 9 x 3 thickness nodes, RGB
    through 81 wavelengths) by PFMC at 2 % and at 4 % (film lookup, as
    bsdflab.scenes.snake tabulates it) and by adding-doubling (``tabulate(...,
    method="adding-doubling")``, table settings for 1 %): CPU and wall seconds, and each
    table's error (luminance, relative, over cells above 1 % of the peak) against a
    reference adding-doubling table (24 nodes, every truncation tighter than the
    solver's defaults). Ratios: PFMC / AD CPU-s as measured (AD also more accurate), and
    at equal max error by the 1/sqrt(N) law from the 2 % run (the exponent measured
    between the 2 % and 4 % runs is printed as a check);
(b) per-direction-pair cost (64 pairs, RGB through 81 wavelengths): PFMC walks to a 1 %
    and a 1e-4 relative standard error (by the 1/sqrt(N) law from one measured run)
    against adding-doubling at table settings (~1 %) and at 32 nodes with 512 azimuth
    samples (~1e-4; the achieved bound is printed);
(c) the spectral fine grid of docs/distributed.md (81 wavelengths stored, 24 x 48 x 25
    directions x 8 thickness nodes = 230 400 cells, 1 %) by adding-doubling, measured
    in full (``--skip-fine`` leaves it out), against the PFMC cost model's 16.6 h on one
    worker.

    python bench/bench_adding_doubling.py [--quick] [--skip-fine] [--only-ad]
"""
from __future__ import annotations

import argparse
import os
import time

import numpy as np

from bsdflab.presets import preset
from bsdflab.scenes.snake import table_grid
from bsdflab.solvers import solve
from bsdflab.tables import TableGrid, tabulate
from bsdflab.tables.channels import LUMINANCE_RGB
from bsdflab.tables.deterministic import table_settings, tabulate_adding_doubling
from bsdflab.testing import random_unit_vectors

REFERENCE = {"azimuth_samples": 256, "spectral_stride": 1, "fine_step": 0.25, "order_tolerance": 1e-7,
             "thin_depth": 2.0 ** -16}
PFMC_FINE_GRID_HOURS = 16.6  # docs/distributed.md: the PFMC cost model on one worker


def timed(fn):
    w, c = time.perf_counter(), time.process_time()
    out = fn()
    return out, time.perf_counter() - w, time.process_time() - c


def errors(table, ref):
    lum, lum_ref = table.values @ LUMINANCE_RGB, ref.values @ LUMINANCE_RGB
    mask = lum_ref > 0.01 * lum_ref.max()
    rel = np.abs(lum[mask] - lum_ref[mask]) / lum_ref[mask]
    return float(rel.max()), float(np.sqrt(np.mean(rel**2)))


def snake_table(model, grid) -> None:
    ref, w_ref, c_ref = timed(lambda: tabulate_adding_doubling(model, grid, nodes=24, solver=REFERENCE))
    ad, w_ad, c_ad = timed(lambda: tabulate(model, grid, method="adding-doubling", progress=False))
    mc, w_mc, c_mc = timed(lambda: tabulate(model, grid, rel_error=0.02, progress=False))
    mc4, w_mc4, c_mc4 = timed(lambda: tabulate(model, grid, rel_error=0.04, progress=False))
    e_ad, e_mc, e_mc4 = errors(ad, ref), errors(mc, ref), errors(mc4, ref)
    p = np.log(c_mc / c_mc4) / np.log(e_mc4[1] / e_mc[1])  # measured: t ~ (RMS error)^-p
    c_equal = c_mc * (e_mc[0] / e_ad[0]) ** 2  # the 1/sqrt(N) law
    print(f"(a) reference AD (24 nodes, tight): {w_ref:.1f} s wall, {c_ref:.1f} CPU-s")
    print(f"    PFMC 2 %: {w_mc:.1f} s wall, {c_mc:.1f} CPU-s; error max {e_mc[0]:.4f}, RMS {e_mc[1]:.4f}")
    print(f"    PFMC 4 %: {w_mc4:.1f} s wall, {c_mc4:.1f} CPU-s; error max {e_mc4[0]:.4f}, RMS {e_mc4[1]:.4f}; "
          f"measured cost law t ~ RMS error^-{p:.2f} (1/sqrt(N): 2)")
    print(f"    AD (table settings {ad.meta['solver']}): {w_ad:.1f} s wall, {c_ad:.1f} CPU-s; error max "
          f"{e_ad[0]:.2e}, RMS {e_ad[1]:.2e}; stated bound max {ad.meta['error_bound_max_rel']:.2e}")
    print(f"    ratio PFMC 2 % / AD: CPU {c_mc / c_ad:.1f}x, wall {w_mc / w_ad:.1f}x, with {e_mc[0] / e_ad[0]:.0f}x "
          f"smaller max error (RMS {e_mc[1] / e_ad[1]:.0f}x)")
    c_law = c_mc * (e_mc[0] / e_ad[0]) ** p
    print(f"    ratio at equal max error ({e_ad[0]:.2e}; PFMC 2 % scaled by 1/sqrt(N)): {c_equal:.3g} CPU-s, "
          f"{c_equal / c_ad:.3g}x; by the measured exponent {p:.2f}: {c_law:.3g} CPU-s, {c_law / c_ad:.3g}x")


def per_pair(model) -> None:
    n = 64
    wi, wo = random_unit_vectors(n, seed=7, hemisphere="upper"), random_unit_vectors(n, seed=8, hemisphere="upper")
    walks = 4096
    (v, s), w_mc, c_mc = timed(lambda: model.eval_with_error(wi, wo, samples=walks))
    rel = float(np.median((s @ LUMINANCE_RGB) / np.abs(v @ LUMINANCE_RGB)))
    per_walk = c_mc / (n * walks)
    for target, kw in ((0.01, table_settings(0.01, 81)), (1e-4, {"nodes": 32, "azimuth_samples": 512})):
        sol = solve(model, None, film_lookup=True, **kw)
        (x, e), w_ad, c_ad = timed(lambda sol=sol: sol.eval_with_error(wi, wo))
        bound = (e @ np.abs(LUMINANCE_RGB)) / np.abs(x @ LUMINANCE_RGB)
        c_pfmc = per_walk * walks * (rel / target) ** 2  # per pair, by the 1/sqrt(N) law
        print(f"(b) {target:g}: PFMC {c_pfmc * 1e3:.3g} CPU-ms per pair (median rel. s.e. {rel:.4f} at {walks} "
              f"walks); AD {c_ad / n * 1e3:.3g} CPU-ms per pair over {n} pairs (bound median {np.median(bound):.1e}, "
              f"max {bound.max():.1e}); ratio {c_pfmc / (c_ad / n):.3g}x")


def fine_grid(model) -> None:
    nodes = table_grid()["thickness_nm"]
    grid = TableGrid(24, 48, 25, tuple(np.linspace(min(nodes), max(nodes), 8)))
    wl = np.linspace(380.0, 780.0, 81)
    table, w, c = timed(lambda: tabulate(model, grid, rel_error=0.01, wavelengths=wl, method="adding-doubling",
                                         progress=False))
    cells = 24 * 48 * 25 * 8
    print(f"(c) spectral fine grid ({cells} cells, 81 wavelengths) by AD: {w:.1f} s wall, {c:.1f} CPU-s "
          f"(stated bound max {table.meta['error_bound_max_rel']:.2e}); PFMC cost model on one worker "
          f"{PFMC_FINE_GRID_HOURS} h = {PFMC_FINE_GRID_HOURS * 3600 / w:.0f}x this wall time")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="a 4 x 6 x 5 x 1 grid instead of the snake's")
    ap.add_argument("--skip-fine", action="store_true", help="leave out (c), the spectral fine grid")
    ap.add_argument("--only-ad", action="store_true", help="only the adding-doubling table of (a) (for profilers)")
    args = ap.parse_args()
    model = preset("xenopeltis")
    grid = TableGrid(4, 6, 5) if args.quick else TableGrid.from_dict(table_grid())
    if args.only_ad:
        ad, w, c = timed(lambda: tabulate(model, grid, method="adding-doubling", progress=False))
        print(f"AD table: {w:.1f} s wall, {c:.1f} CPU-s, stated bound max {ad.meta['error_bound_max_rel']:.2e}")
        return
    print(f"grid {grid.n_theta_i} x {grid.n_theta_o} x {grid.n_phi} x {max(1, len(grid.thickness_nm))} "
          f"thickness nodes, RGB, {os.cpu_count()} cores, load {os.getloadavg()[0]:.1f}")
    snake_table(model, grid)
    per_pair(model)
    if not args.skip_fine:
        fine_grid(model)
    print(f"load at the end {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
