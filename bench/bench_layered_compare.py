"""Layered estimators side by side: efficiency of "pfmc2" against "pfmc" in one run.

Efficiency = 1 / (variance x time): the relative variance of one estimate (of the
configuration's projected output) times the CPU seconds it took (all threads; robust to
other processes on a shared machine), per direction pair, median over the pairs;
printed as the ratio pfmc2 / pfmc (> 1: pfmc2 reaches an error in less time). Both
estimators run on the same pairs, one after the other, best of `--repeats` timings.

Configurations: the snake preset (luminance of 81 wavelengths), the scattering cases of
tests/layered/test_layered_vs_adding_doubling.py (mean of their 3 channels), a thick
bright slab (tau 10, albedo 0.99, white base), a rough conductor base under a rough
top. With --tabulate: the snake table's tabulation time (RGB, a small grid, equal target error); with
--service: the cost of one eval of the preset at 1 % luminance error (the service's eval).
Run: python3 bench/bench_layered_compare.py [--pairs 16] [--walks 2000] [--tabulate] [--service]
"""
from __future__ import annotations

import argparse
import time

import numpy as np

import bsdflab as bl
from bsdflab import _core
from bsdflab.spectra import DEFAULT_WAVELENGTHS, Spectrum, srgb_weights
from bsdflab.tables.channels import LUMINANCE_RGB
from bsdflab.testing import random_unit_vectors

ESTIMATORS = ("pfmc", "pfmc2")
WL3 = [450.0, 550.0, 650.0]


def _slab(tau, albedos, phase=None, thickness=1.0):
    sigma_s = float(np.max(albedos)) * tau / thickness
    sigma_a = sigma_s / np.asarray(albedos, dtype=float) - sigma_s
    return bl.Slab(thickness, sigma_a=Spectrum.tabulated(WL3, sigma_a), sigma_s=sigma_s, phase=phase)


FWD, BACK = {"type": "hg", "g": 0.6}, {"type": "hg", "g": -0.3}
TOP = bl.Dielectric(1.5, 1.0)


def configurations():
    """name -> (layers (interfaces, slabs, base), wavelengths, projection row (C,), transmission)."""
    wl = np.asarray(DEFAULT_WAVELENGTHS, dtype=float)
    lum = LUMINANCE_RGB @ srgb_weights(wl)
    mean3 = np.full(3, 1.0 / 3.0)
    snake = bl.presets.xenopeltis()
    rough_top = bl.RoughDielectric(0.3, int_ior=1.5, ext_ior=1.0)
    return {
        "snake (xenopeltis, Y)": ((snake.interfaces, snake.slabs, snake.base), wl, lum, False),
        "iso tau1 w.5-.9 lambert": (([TOP], [_slab(1.0, [0.5, 0.7, 0.9])], bl.Diffuse(0.5)), WL3, mean3, False),
        "hg.6 tau5 w.9-.99 black": (([TOP], [_slab(5.0, [0.9, 0.95, 0.99], FWD)], bl.Diffuse(0.0)), WL3, mean3,
                                    False),
        "hg-.3 tau.5 w.5-.95 lambert": (([TOP], [_slab(0.5, [0.5, 0.8, 0.95], BACK)], bl.Diffuse(0.8)), WL3,
                                        mean3, False),
        "hg.6 tau2 w.7-.99 glass (T)": (([TOP], [_slab(2.0, [0.7, 0.9, 0.99], FWD)], bl.Dielectric(1.0, 1.5)),
                                        WL3, mean3, True),
        "iso tau3 matched (T)": (([bl.Dielectric(1.5, 1.5)], [_slab(3.0, [0.5, 0.9, 0.99])],
                                  bl.Dielectric(1.5, 1.5)), WL3, mean3, True),
        "thick bright tau10 w.99": (([TOP], [_slab(10.0, [0.99, 0.99, 0.99])], bl.Diffuse(1.0)), WL3, mean3,
                                    False),
        "rough conductor base": (([rough_top], [_slab(1.0, [0.6, 0.8, 0.95], FWD)],
                                  bl.RoughConductor(0.2, eta=0.2, k=3.0, ext_ior=1.5)), WL3, mean3, False),
    }


def efficiency(core, wi, wo, walks, row, repeats):
    """Median over pairs of 1 / (relative variance of one estimate x seconds per pair)."""
    best = np.inf
    for _ in range(repeats):
        t0 = time.process_time()  # CPU seconds of all threads: robust to other processes' load
        value, err, bad, capped = core.estimate(wi, wo, int(bl.Lobe.ALL), None, walks, 7)
        best = min(best, time.process_time() - t0)
    assert bad == 0 and capped == 0
    mean, se = value @ row, err @ np.abs(row)
    ok = mean > 0
    rel_var = (se[ok] / mean[ok]) ** 2
    return 1.0 / (np.median(rel_var) * best / len(wi)), best / len(wi), np.median(rel_var) * walks


def compare(pairs, walks, repeats):
    print(f"{_core.worker_count()} threads, {pairs} pairs, {walks} walks per pair, best of {repeats}")
    print(f"  {'configuration':30s} {'CPU-us/walk pfmc':>16s} {'pfmc2':>7s} {'relvar/walk pfmc':>17s} "
          f"{'pfmc2':>8s} {'efficiency pfmc2/pfmc':>22s}")
    ratios = {}
    for name, ((ifs, slabs, base), wl, row, transmit) in configurations().items():
        wi = random_unit_vectors(pairs, seed=11, hemisphere="upper")
        wo = random_unit_vectors(pairs, seed=12, hemisphere="upper")
        if transmit:
            wo[pairs // 2:, 2] *= -1.0
        res = {}
        for est in ESTIMATORS:
            core = bl.Layered(list(ifs), list(slabs), base, estimator=est)._core(np.asarray(wl, dtype=float))
            res[est] = efficiency(core, wi, wo, walks, row, repeats)
        ratios[name] = res["pfmc2"][0] / res["pfmc"][0]
        print(f"  {name:30s} {1e6 * res['pfmc'][1] / walks:16.2f} {1e6 * res['pfmc2'][1] / walks:7.2f} "
              f"{res['pfmc'][2]:17.3g} {res['pfmc2'][2]:8.3g} {ratios[name]:21.2f}x")
    return ratios


def time_to_one_percent(est, pairs):
    """CPU seconds per pair for a 1 % luminance error on the snake (walks from a pilot run):
    what an eval of the preset at that error costs the service."""
    m = bl.presets.xenopeltis(samples=256)
    wl = np.asarray(DEFAULT_WAVELENGTHS, dtype=float)
    lum = LUMINANCE_RGB @ srgb_weights(wl)
    core = bl.Layered(list(m.interfaces), list(m.slabs), m.base, estimator=est)._core(wl)
    wi = random_unit_vectors(pairs, seed=21, hemisphere="upper")
    wo = random_unit_vectors(pairs, seed=22, hemisphere="upper")
    _, t, rv = efficiency(core, wi, wo, 1000, lum, 1)
    walks = int(np.ceil(rv / 1e-4))
    t0 = time.process_time()
    value, err, _, _ = core.estimate(wi, wo, int(bl.Lobe.ALL), None, walks, 9)
    dt = (time.process_time() - t0) / pairs
    rel = np.median((err @ np.abs(lum)) / (value @ lum))
    return walks, dt, rel


def tabulate_snake(est, rel_error):
    """CPU seconds of a snake table (RGB) on a small grid with two film-thickness nodes."""
    from bsdflab.tables import TableGrid, tabulate
    m0 = bl.presets.xenopeltis()
    m = bl.Layered(list(m0.interfaces), list(m0.slabs), m0.base, estimator=est)
    t0 = time.process_time()
    table = tabulate(m, TableGrid(4, 8, 5, thickness_nm=(350.0, 450.0)), rel_error=rel_error, progress=False)
    return time.process_time() - t0, table


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--pairs", type=int, default=16)
    ap.add_argument("--walks", type=int, default=2000)
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--tabulate", action="store_true", help="also time the snake table")
    ap.add_argument("--service", action="store_true", help="also time 1 %% luminance evals of the preset")
    args = ap.parse_args()
    compare(args.pairs, args.walks, args.repeats)
    if args.service:
        print("snake, 1 % relative luminance error per pair (walks from a pilot run):")
        for est in ESTIMATORS:
            walks, dt, rel = time_to_one_percent(est, args.pairs)
            print(f"  {est:6s} {walks:6d} walks, {1e3 * dt:7.2f} CPU-ms per pair (reached {100 * rel:.2f} %)")
    if args.tabulate:
        print("snake table (RGB, 4 x 8 x 5 x 2 thickness nodes, 2 % target), CPU seconds:")
        for est in ESTIMATORS:
            dt, table = tabulate_snake(est, 0.02)
            print(f"  {est:6s} {dt:7.1f} CPU-s  {int(table.samples.sum())} walks  "
                  f"rms error {table.meta['rel_error_rms']:.4f}")


if __name__ == "__main__":
    main()
