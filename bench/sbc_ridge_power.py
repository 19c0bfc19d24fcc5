"""Power of the SBC family (tests/support/sbc.py, ``joint=True``) against posteriors too
narrow along the film thickness-index ridge only: Gaussian posteriors with the structure
fit's correlations (thickness-index -0.995, scale-background -0.84), the ridge direction's
variance scaled by shrink^2, 300 draws each; prints the rejection rate of the joint sum and
of the ridge test per shrink.

    python bench/sbc_ridge_power.py [--datasets 48] [--reps 150]
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from support.sbc import calibration_failures  # noqa: E402

SD = np.array([4.3, 0.0075, 0.02, 0.002, 3.0])
CORR = np.eye(5)
CORR[0, 1] = CORR[1, 0] = -0.995
CORR[2, 3] = CORR[3, 2] = -0.84


def rejection(n: int, shrink: float, reps: int, seed: int) -> dict[str, float]:
    rng = np.random.default_rng(seed)
    w, v = np.linalg.eigh(CORR)
    w_reported = w.copy()
    w_reported[-1] *= shrink ** 2
    true_chol = np.linalg.cholesky(CORR * np.outer(SD, SD))
    reported_chol = np.linalg.cholesky((v @ np.diag(w_reported) @ v.T) * np.outer(SD, SD))
    counts = {"sum z^2": 0, "ridge u^2": 0}
    for _ in range(reps):
        truths = rng.standard_normal((n, 5)) @ true_chol.T  # truth - posterior mean ~ N(0, true cov)
        posteriors = [rng.standard_normal((300, 5)) @ reported_chol.T for _ in range(n)]
        names = {f[0] for f in calibration_failures(truths, posteriors, bins=3, joint=True)}
        for k in counts:
            counts[k] += k in names
    return {k: c / reps for k, c in counts.items()}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--datasets", type=int, default=48)
    ap.add_argument("--reps", type=int, default=150)
    args = ap.parse_args()
    for shrink in (1.0, 0.85, 0.7):
        print(f"ridge sd x {shrink}: rejected", rejection(args.datasets, shrink, args.reps, seed=1))


if __name__ == "__main__":
    main()
