"""The pooled per-pair error of ``Layered.estimate`` states the value's variance without
bias at efforts where pfmc2's walk groups are unequal or single (docs/coverage.md "Per pair").

pfmc2 averages group means (groups of 4 walks sharing a delta chain, a short last group),
so 9 walks as 4, 4, 1 have the variance of 6 equal walks; pooling the extra walks' spread
as se^2 x walks stated that variance 0.7x (samples=9), and a 1-walk value (1 group) kept
an error of 0 though its 4 extra walks measure the spread.

Independent reference: two estimates at independent seeds s, s' have
E[(X_s - X_s')^2 / 2] = Var X, so D = (X_s - X_s')^2 / 2 - (se_s^2 + se_s'^2) / 2 has mean 0
exactly when E[se^2] = Var X. Per seed pair, T = sum over the 24 pairs and 3 channels of
D / f^2 (f: a 20 000-walk estimate, fixed weights that put the pairs on one scale); the
500 seed pairs give iid T, and a two-sided one-sample t-test (CLT: T's skewness ~1.5,
its mean's ~0.07) must not reject at alpha 0.005 per case (family 0.01, Sidak over 2).
1000 seeds (was 2000: 7.1 -> 3.2 CPU-s, both cases); t grows as sqrt(seeds), so the
power figures below (at 2000) read ~1/sqrt(2) of them. Mutation: Layered.estimate's
stderr scaled by 0.9 (stated variance 0.81x) fails both cases.

Power (the previous walk_statistics.cpp, se^2 x walks through pooled_error, run once):
samples=1: t = 51.4 (error 0); samples=9: t = 22.4 (stated/empirical variance 0.715).
This code: t = 0.93 and 0.36 (ratios 1.00, 0.98). The value's own error (error_walks=0)
passes at samples=9 too (t = -0.54): its groups are independent, so it is unbiased.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

import bsdflab as bl
from bsdflab.testing import random_unit_vectors, sidak_significance

WL = [450.0, 550.0, 650.0]
PAIRS = 24
SEEDS = 1000
ALPHA = sidak_significance(0.01, 2)


def coated_diffuse():
    # smooth top: pfmc2 shares each delta chain between groups of 4 walks
    return bl.Layered(
        [bl.Dielectric(1.5)], [bl.Slab(0.2, sigma_a=0.5, sigma_s=0.5)], bl.Diffuse(0.6), estimator="pfmc2"
    )


@pytest.mark.parametrize("samples", [1, 9])
def test_pooled_error_states_the_values_variance(samples):
    model = coated_diffuse()
    wi = random_unit_vectors(PAIRS, seed=11, hemisphere="upper")
    wo = random_unit_vectors(PAIRS, seed=12, hemisphere="upper")
    f = model.estimate(wi, wo, WL, samples=20000, seed=99, scattered_only=True, error_walks=0).value
    assert np.all(f > 0)
    runs = [model.estimate(wi, wo, WL, samples=samples, seed=s, scattered_only=True) for s in range(SEEDS)]
    x = np.array([r.value for r in runs])
    var = np.array([r.stderr for r in runs]) ** 2
    d = (x[0::2] - x[1::2]) ** 2 / 2 - (var[0::2] + var[1::2]) / 2
    t_stat = (d / f**2).sum(axis=(1, 2))
    result = stats.ttest_1samp(t_stat, 0.0)
    ratio = var.mean(axis=0).sum() / x.var(axis=0, ddof=1).sum()
    assert result.pvalue >= ALPHA, (
        f"samples={samples}: t = {result.statistic:.2f}, p = {result.pvalue:.2g}; stated/empirical variance {ratio:.3f}"
    )
