"""Simulation-based calibration statistics (Talts et al. 2018) shared by the fit tests.

Each family is Sidak-corrected at ALPHA_SBC (a calibrated fit fails it 1 time in 1000):
the sum of squared posterior z-scores (one test), coverage of the central 90 % intervals
and rank uniformity (one chi-square) per parameter. The z-sum carries the power: for a
calibrated posterior E[z^2] = 1 exactly (z = (truth - posterior mean) / posterior sd, any
posterior shape), so sum z^2 over the datasets and parameters is close to chi^2 with
ndim x n degrees of freedom; a posterior whose sd is r times the true one gives z^2 / r^2.
"""
from __future__ import annotations

import numpy as np
from scipy import stats

ALPHA_SBC = 0.001
NARROW = 0.7  # the mis-calibration the check must catch: posterior sd 0.7 x the true one


def family_size(ndim: int, joint: bool = False) -> int:
    return 1 + 2 * ndim + int(joint)


def z_sum_limits(n_datasets: int, ndim: int = 2, alpha: float = ALPHA_SBC, joint: bool = False):
    """Two-sided acceptance interval of sum z^2 (chi^2, ndim x n degrees of freedom)."""
    a = 1 - (1 - alpha) ** (1 / family_size(ndim, joint))
    k = ndim * n_datasets
    return stats.chi2.ppf(a / 2, k), stats.chi2.ppf(1 - a / 2, k)


def z_sum_power(n_datasets: int, ndim: int = 2, narrow: float = NARROW) -> float:
    """Probability that sum z^2 leaves its acceptance interval when every posterior sd is
    ``narrow`` times the true one (sum z^2 is then chi^2(ndim n) / narrow^2)."""
    lo, hi = z_sum_limits(n_datasets, ndim)
    k = ndim * n_datasets
    return stats.chi2.sf(hi * narrow ** 2, k) + stats.chi2.cdf(lo * narrow ** 2, k)


def narrowed(draws, factor):
    """The same posterior draws, their spread about the mean scaled by ``factor`` (a sampler
    or likelihood that reports too narrow a posterior, for the power check)."""
    mean = draws.mean(axis=0)
    return mean + factor * (draws - mean)


def calibration_failures(truths, posteriors, bins, seed=0, ranks_from=19, joint=False):
    """The calibration tests that reject (an empty list when the posteriors are calibrated).
    truths (n, ndim); posteriors: one (draws, ndim) array per dataset.

    ``joint``: the z-sum is replaced by the sum of squared Mahalanobis distances of the truths
    from the posterior means in the posteriors' own covariances, (t - m)^T S^-1 (t - m). Its
    expectation is ndim per dataset for any calibrated posterior, as the z-sum's, and it is
    chi^2(ndim) for a Gaussian one whatever the posterior correlations; the z-sum's variance
    is 2 tr(R^2) per dataset (R the posterior correlation matrix), not 2 ndim, so with strongly
    correlated parameters (a free film index: thickness-index -0.995, z_d = -z_n) its chi^2
    band is too narrow and it rejects calibrated posteriors. Power against posteriors narrowed
    by r is the z-sum's (both scale by 1 / r^2) only for a uniform narrowing: a posterior too
    narrow along the ridge alone moves one of ndim terms, which the joint sum dilutes (a
    review's simulation: ridge-only 0.85 x rejected 0.3 % of the time at 48 datasets against
    the plain sum's 10 %). So ``joint`` adds one test to the family: the squared standardised
    distance along each posterior's largest-variance direction of its correlation matrix (the
    ridge), u^2, summed over the datasets, chi^2(n) when calibrated."""
    rng = np.random.default_rng(seed)
    n, ndim = truths.shape
    a = 1 - (1 - ALPHA_SBC) ** (1 / family_size(ndim, joint))
    failed = []
    draws_mean = np.array([d.mean(axis=0) for d in posteriors])
    draws_sd = np.array([d.std(axis=0, ddof=1) for d in posteriors])
    z = (truths - draws_mean) / draws_sd
    if joint:
        total = sum(float(r @ np.linalg.solve(np.cov(d, rowvar=False), r))
                    for d, r in zip(posteriors, truths - draws_mean, strict=True))
        ridge = 0.0
        for d, zi in zip(posteriors, z, strict=True):
            lam, vec = np.linalg.eigh(np.corrcoef(d, rowvar=False))
            ridge += float(vec[:, -1] @ zi) ** 2 / lam[-1]
        r_lo, r_hi = stats.chi2.ppf(a / 2, n), stats.chi2.ppf(1 - a / 2, n)
        if not r_lo <= ridge <= r_hi:
            failed.append(("ridge u^2", ridge, (r_lo, r_hi)))
    else:
        total = float(np.sum(z ** 2))
    lo, hi = z_sum_limits(n, ndim, joint=joint)
    if not lo <= total <= hi:
        failed.append(("sum z^2", total, (lo, hi)))
    # coverage of the central 90 % interval: Binomial(n, 0.9), two-sided band at level a
    bounds = np.array([np.quantile(d, [0.05, 0.95], axis=0) for d in posteriors])
    counts = ((bounds[:, 0] < truths) & (truths < bounds[:, 1])).sum(axis=0)
    c_lo, c_hi = stats.binom.ppf(a / 2, n, 0.9), stats.binom.ppf(1 - a / 2, n, 0.9)
    for j in range(ndim):
        if not c_lo <= counts[j] <= c_hi:
            failed.append((f"coverage {j}", int(counts[j]), (c_lo, c_hi)))
    # ranks of the truth among ranks_from draws: uniform on 0..ranks_from
    ranks = np.array([np.sum(d[rng.choice(len(d), ranks_from, replace=False)] < t, axis=0)
                      for d, t in zip(posteriors, truths, strict=True)])
    for j in range(ndim):
        hist = np.histogram(ranks[:, j], bins=bins, range=(0, ranks_from + 1))[0]
        p = stats.chisquare(hist).pvalue
        if not p > a:
            failed.append((f"ranks {j}", hist.tolist(), p))
    return failed
