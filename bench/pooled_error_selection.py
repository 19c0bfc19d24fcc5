"""How much the pooled cell error (core/src/tabulation.cpp pooled_error) is pulled down by
choosing the final walk count n from the same pilot whose spread it pools.

Synthetic walks (lognormal, sigma chosen so the effort rule's clamp at n0 binds for part of
the cells), the tabulator's rule n = clamp(1.1 n0 (se0 / (rel lum0))^2, n0, max), the pooled
variance per walk against the true one, split by n = n0 (clamped) and n > n0.

    python bench/pooled_error_selection.py [--cells 20000]
"""
from __future__ import annotations

import argparse

import numpy as np


def study(sigma: float, n0: int, cells: int, rel: float = 0.05, seed: int = 1) -> None:
    rng = np.random.default_rng(seed)
    var = np.exp(sigma**2) * (np.exp(sigma**2) - 1)  # per-walk variance of lognormal(0, sigma)
    ratio, clamped = np.empty(cells), np.empty(cells, bool)
    for i in range(cells):
        p = rng.lognormal(0, sigma, n0)
        s0 = p.var(ddof=1)
        n = int(np.clip(1.1 * n0 * s0 / n0 / (rel * p.mean()) ** 2, n0, 1 << 16))
        s1 = rng.lognormal(0, sigma, n).var(ddof=1)
        ratio[i] = ((n0 - 1) * s0 + (n - 1) * s1) / (n0 + n - 2) / var
        clamped[i] = n == n0
    se = lambda x: x.std(ddof=1) / np.sqrt(max(len(x), 1))  # noqa: E731
    print(f"sigma {sigma} n0 {n0}: E[pooled var / var] all {ratio.mean():.3f} +- {se(ratio):.3f}; "
          f"n = n0 ({clamped.mean():.0%} of cells) {ratio[clamped].mean():.3f} +- {se(ratio[clamped]):.3f}; "
          f"n > n0 {ratio[~clamped].mean():.3f} +- {se(ratio[~clamped]):.3f}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cells", type=int, default=20000)
    args = ap.parse_args()
    for sigma in (0.85, 1.0):
        study(sigma, 512, args.cells)


if __name__ == "__main__":
    main()
