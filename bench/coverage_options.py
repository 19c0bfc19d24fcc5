"""Error estimators for a table cell under heavy tails, compared by a bootstrap from real
walks (docs/coverage.md, "Options tried").

Draws --walks single snake walks (550 nm, the scattered part) at four direction pairs,
then resamples the tabulator's rule from them (pilot of n0 walks, finish n =
clamp(1.1 n0 (se / target)^2, n0, 65536) fresh walks, target = rel_error x pilot mean) and
prints, per pair, n0 and error estimator, the walks per cell and the share of cells with
|mean - truth| > k error (truth: the mean of all drawn walks) over the normal share:
fresh (version 6), pooled (version 7: pilot and fresh spread pooled), max (the larger).
Run: python bench/coverage_options.py [--walks 200000] [--cells 60000]
"""
from __future__ import annotations

import argparse

import numpy as np
from scipy import stats

import bsdflab as bl
from bsdflab.presets import preset
from bsdflab.testing import spherical_directions

KS = np.array([2.0, 3.0, 4.0])
PAIRS = ((10, 20, 1.0), (60, 70, 0.5), (80, 80, 1.0), (40, 40, 0.0))


def walks(pair, count: int) -> np.ndarray:
    core = preset("xenopeltis")._core(np.array([550.0])).scattered_part()
    ti, to, po = pair
    a = spherical_directions(np.radians(ti), 0.0)[None]
    b = spherical_directions(np.radians(to), np.pi * po)[None]
    # samples=1 per seed: independent single walks
    return np.array([core.estimate(a, b, int(bl.Lobe.ALL), None, 1, s)[0][0, 0] for s in range(count)])


def shares(x: np.ndarray, n0: int, cells: int, rel_error: float, rng, chunk: int = 5000):
    mu, p0 = x.mean(), 2 * stats.norm.sf(KS)
    counts = {name: np.zeros(len(KS)) for name in ("fresh", "pooled", "max")}
    spent = 0
    for _ in range(cells // chunk):
        pilot = x[rng.integers(0, x.size, size=(chunk, n0))]
        s0 = pilot.std(1, ddof=1)
        n = np.clip(np.ceil(1.1 * n0 * (s0 / np.sqrt(n0) / (rel_error * np.abs(pilot.mean(1)))) ** 2),
                    n0, 65536).astype(int)
        fresh = x[rng.integers(0, x.size, size=(chunk, n.max()))]
        used = np.arange(n.max())[None, :] < n[:, None]
        m = (fresh * used).sum(1) / n
        s1 = np.sqrt((((fresh - m[:, None]) ** 2) * used).sum(1) / (n - 1))
        spent += int((n + n0).sum())
        pooled = np.sqrt(((n0 - 1) * s0**2 + (n - 1) * s1**2) / (n0 + n - 2))
        for name, s in (("fresh", s1), ("pooled", pooled), ("max", np.maximum(s0, s1))):
            z = (m - mu) / (s / np.sqrt(n))
            counts[name] += [np.count_nonzero(np.abs(z) > k) for k in KS]
    done = cells // chunk * chunk
    return {name: c / done / p0 for name, c in counts.items()}, spent / done


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--walks", type=int, default=200_000)
    ap.add_argument("--cells", type=int, default=60_000)
    ap.add_argument("--rel-error", type=float, default=0.05)
    args = ap.parse_args()
    rng = np.random.default_rng(2)
    print("share beyond k = 2, 3, 4 over the normal share")
    for pair in PAIRS:
        x = walks(pair, args.walks)
        for n0 in (512, 1024):
            r, spent = shares(x, n0, args.cells, args.rel_error, rng)
            cols = "  ".join(f"{name} {np.round(v, 2)}" for name, v in r.items())
            print(f"pair {pair} n0 {n0}: {spent:.0f} walks/cell  {cols}", flush=True)


if __name__ == "__main__":
    main()
