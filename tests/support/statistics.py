"""z-tests of stochastic estimates against a reference, shared by the layered tests.

A PFMC estimate v with standard error s is compared with a reference r by z = (v - r) / s.
Over n values max |z| stays below the two-sided Sidak-corrected normal quantile at
family-wise significance 0.01; per channel over the independent pairs, sum z^2 stays within
the chi^2 quantiles.
"""
from __future__ import annotations

import numpy as np
from scipy import stats

from bsdflab.testing import sidak_z_limit

SIGNIFICANCE = 0.01


def z_limit(n: int, alpha: float = SIGNIFICANCE) -> float:
    return sidak_z_limit(alpha, n)


def assert_agrees(value, err, ref, what="", model_error=None, family: int = 1):
    """z-tests of estimates against a reference. Arrays are (pairs,) or (pairs, channels).
    ``family``: how many such calls share the family-wise significance (a parametrized
    test's cases), Sidak-corrected across them too.

    max |z| over everything is held below the Sidak quantile (valid for the positively
    correlated channels, which share walks). The sum of z^2 is tested per channel over the
    independent pairs (chi^2 with `pairs` dof), at significance 0.01 / channels. With a
    (non-statistical) model error term only the upper bounds apply."""
    total = err if model_error is None else np.hypot(err, model_error)
    z = np.atleast_2d(((value - ref) / total).T).T.reshape(np.shape(value)[0], -1)
    n_pairs, channels = z.shape
    limit = z_limit(z.size * family)
    assert np.max(np.abs(z)) < limit, f"{what}: max |z| = {np.max(np.abs(z)):.2f} >= {limit:.2f}"
    alpha = SIGNIFICANCE / (channels * family)
    lo, hi = stats.chi2.ppf([alpha / 2, 1 - alpha / 2], n_pairs)
    for c in range(channels):
        chi2 = np.sum(z[:, c] ** 2)
        assert chi2 < hi, f"{what}: channel {c}: sum z^2 = {chi2:.1f} > {hi:.1f} (n = {n_pairs})"
        if model_error is None:
            assert chi2 > lo, f"{what}: channel {c}: sum z^2 = {chi2:.1f} < {lo:.1f}: errors overstated"
