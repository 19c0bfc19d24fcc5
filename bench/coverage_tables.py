"""Coverage of PFMC standard errors against adding-doubling (issue 32 item 1).

For each stack and estimator (pfmc2, pfmc) this draws many independent PFMC estimates of
quantities adding-doubling knows to ~1e-4 and counts how often |PFMC - AD| exceeds k
reported standard errors, against the normal expectation 2 (1 - Phi(k)), k = 2, 3, 4:

* **tables** -- ``tabulate`` (pilot + finish, the user's settings) at seeds 0..S-1 on a
  small grid; per cell one channel (channel = (seed + cell) mod 3, so the counted cells
  are independent: channels of one cell share walks);
* **pairs** -- ``Layered.estimate(..., scattered_only=True)`` at ``--samples`` walks (the
  model's default effort, 256) for P direction pairs x S seeds, one channel per pair, with
  ``--error-walks M`` x samples extra walks for the error (default: Layered.estimate's).

z = (PFMC - AD) / hypot(PFMC stderr, AD error bound). Per k it prints the observed fraction,
the expectation and the two-sided binomial p-value of the count (the units are
independent, so the binomial is exact); 'ok' when p >= 0.01/3 (Sidak over k = 2, 3, 4).
Run: python bench/coverage_tables.py [--seeds 200] [--what tables pairs] [--models ...] [--error-walks M]
"""
from __future__ import annotations

import argparse
import time

import numpy as np
from scipy import stats

import bsdflab as bl
from bsdflab.presets import preset
from bsdflab.solvers import solve
from bsdflab.tables import TableGrid, tabulate
from bsdflab.testing import random_unit_vectors

WL = [450.0, 550.0, 650.0]
GRID = TableGrid(3, 4, 3, thickness_nm=(350.0, 450.0))
KS = (2.0, 3.0, 4.0)
ALPHA = 0.01 / len(KS)


def models() -> dict[str, object]:
    """Heavy-tailed stacks that adding-doubling solves tightly (bench/bench_layered_tails.py)."""
    return {
        "snake": lambda est: bl.from_dict({**preset("xenopeltis").to_dict(), "estimator": est}),
        "plastic": lambda est: bl.Layered([bl.Dielectric(1.5)], [bl.Slab(1.0, sigma_a=0.2, sigma_s=1.0)],
                                          bl.Diffuse(0.6), estimator=est),
        "bright": lambda est: bl.Layered([bl.RoughDielectric(0.3, 1.5)],
                                         [bl.Slab(2.0, sigma_a=0.02, sigma_s=2.0)],
                                         bl.Diffuse(0.8), estimator=est),
    }


def count_report(z: np.ndarray) -> list[tuple[float, float, float, int, int, float]]:
    """Per k: (k, observed fraction, expected fraction, count, units, binomial p-value)."""
    z = z[np.isfinite(z)]
    rows = []
    for k in KS:
        p0 = 2 * stats.norm.sf(k)
        c = int(np.count_nonzero(np.abs(z) > k))
        rows.append((k, c / z.size, p0, c, z.size, float(stats.binomtest(c, z.size, p0).pvalue)))
    return rows


def print_report(label: str, z: np.ndarray) -> bool:
    ok = True
    for k, obs, exp, c, n, p in count_report(z):
        good = p >= ALPHA
        ok &= good
        print(f"  {label:34s} k={k:.0f}: {obs:.5f} ({c:5d}/{n}) expected {exp:.5f}  p={p:.2g}  "
              f"{'ok' if good else 'MISCOVERED'}")
    neg = np.mean(z < 0)
    print(f"  {label:34s} mean z {z.mean():+.3f}, sd {z.std():.3f}, share below AD {neg:.3f}")
    return ok


def table_z(model, ad, seeds, rel_error, min_samples) -> np.ndarray:
    zs = []
    for seed in seeds:
        mc = tabulate(model, GRID, rel_error=rel_error, wavelengths=WL, progress=False, seed=int(seed),
                      min_samples=min_samples)
        z = (mc.values - ad.values) / np.hypot(mc.stderr, ad.stderr)
        z = z.reshape(-1, z.shape[-1])
        ch = (seed + np.arange(len(z))) % z.shape[-1]
        zs.append(z[np.arange(len(z)), ch])
    return np.concatenate(zs)


def pair_z(model, sol, seeds, pairs, samples, error_walks=None) -> np.ndarray:
    wi = random_unit_vectors(pairs, seed=11, hemisphere="upper")
    wo = random_unit_vectors(pairs, seed=12, hemisphere="upper")
    ref, ref_err = sol.eval_with_error(wi, wo, scattered_only=True)
    zs = []
    for seed in seeds:
        e = model.estimate(wi, wo, WL, samples=samples, seed=int(seed), scattered_only=True,
                           error_walks=error_walks)
        z = (e.value - ref) / np.hypot(e.stderr, ref_err)
        ch = (seed + np.arange(pairs)) % z.shape[-1]
        zs.append(z[np.arange(pairs), ch])
    return np.concatenate(zs)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seeds", type=int, default=200)
    ap.add_argument("--what", nargs="+", default=["tables", "pairs"], choices=["tables", "pairs"])
    ap.add_argument("--models", nargs="+", default=list(models()), choices=list(models()))
    ap.add_argument("--estimators", nargs="+", default=["pfmc2", "pfmc"], choices=["pfmc2", "pfmc"])
    ap.add_argument("--rel-error", type=float, default=0.05)
    ap.add_argument("--min-samples", type=int, default=512)
    ap.add_argument("--pairs", type=int, default=24)
    ap.add_argument("--samples", type=int, default=256)
    ap.add_argument("--error-walks", type=int, default=None,
                    help="pairs: extra walks for the error per walk of the value (default: "
                         "the library's, Layered.estimate's error_walks; 0: the value's walks alone)")
    args = ap.parse_args()
    extra = None if args.error_walks is None else args.error_walks * args.samples
    seeds = np.arange(args.seeds)
    print(f"{args.seeds} seeds; tables: grid {GRID.n_theta_i}x{GRID.n_theta_o}x{GRID.n_phi}x"
          f"{len(GRID.thickness_nm)}, rel_error {args.rel_error}, min_samples {args.min_samples}; "
          f"pairs: {args.pairs} x {args.samples} walks, error_walks "
          f"{'default' if extra is None else extra}; wavelengths {WL}")
    ok = True
    for name in args.models:
        make = models()[name]
        base = make("pfmc2")
        if "tables" in args.what:
            ad = tabulate(base, GRID, rel_error=0.002, wavelengths=WL, method="adding-doubling", progress=False)
            print(f"{name}: AD table error bound max rel {ad.meta['error_bound_max_rel']:.2g}")
        if "pairs" in args.what:
            sol = solve(base, WL)
        for est in args.estimators:
            model = make(est)
            if "tables" in args.what:
                t = time.perf_counter()
                ok &= print_report(f"{name} table {est}", table_z(model, ad, seeds, args.rel_error,
                                                                 args.min_samples))
                print(f"  ({time.perf_counter() - t:.0f} s)")
            if "pairs" in args.what:
                t = time.perf_counter()
                ok &= print_report(f"{name} pairs {est}", pair_z(model, sol, seeds, args.pairs, args.samples,
                                                                   extra))
                print(f"  ({time.perf_counter() - t:.0f} s)")
    print("all covered" if ok else "MISCOVERED somewhere")


if __name__ == "__main__":
    main()
