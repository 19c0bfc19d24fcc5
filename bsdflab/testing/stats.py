"""Statistical building blocks of the goodness-of-fit tests: cell pooling, Pearson's
chi-square with its p-value, and the Sidak multiple-test correction.

These are exposed so that their behaviour can be checked on tiny inputs with known
answers, and reused for tests over other discrete domains.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import stats as sps

from bsdflab.testing.directions import positive_int


@dataclass(frozen=True)
class PooledCells:
    """Cells after pooling: regular cells first, then the single pooled cell (if any)."""

    observed: np.ndarray  # (K,)
    expected: np.ndarray  # (K,)
    pooled_in: int        # how many original cells went into the pooled cell (0 = none)


@dataclass(frozen=True)
class PearsonResult:
    """Pearson's chi-square statistic over pooled cells."""

    statistic: float
    dof: int          # pooled cell count - 1
    p_value: float    # NaN when dof < 1 (nothing to test)
    cells: int        # cell count after pooling
    pooled_in: int    # original cells merged into the pooled cell


def sidak_significance(significance: float, test_count: int = 1) -> float:
    """Per-test significance level so that ``test_count`` independent tests together
    wrongly reject a true hypothesis with probability ``significance``.

    Parameters
    ----------
    significance : float in (0, 1)
        Family-wise significance level alpha.
    test_count : int >= 1
        Number of tests run in the family.

    Returns
    -------
    float
        ``1 - (1 - alpha) ** (1 / test_count)``.

    Examples
    --------
    >>> round(sidak_significance(0.05, 2), 6)
    0.025321
    """
    alpha = check_significance(significance)
    m = positive_int("test_count", test_count)
    return 1.0 - (1.0 - alpha) ** (1.0 / m)


def sidak_z_limit(significance: float, test_count: int = 1) -> float:
    """The |z| below which each of ``test_count`` two-sided normal z-tests passes, so that
    together they wrongly reject a true hypothesis with probability ``significance``
    (Sidak): the normal quantile at 1 - ``sidak_significance(...)`` / 2.

    Examples
    --------
    >>> round(sidak_z_limit(0.01, 64), 2)
    3.78
    """
    return float(sps.norm.isf(sidak_significance(significance, test_count) / 2))


def pool_low_expected(observed, expected, min_expected: float = 5.0) -> PooledCells:
    """Merge cells with too few expected counts so the chi-square approximation holds.

    Cells with ``expected < min_expected`` are summed into one pooled cell. If that
    cell is itself still below ``min_expected``, the smallest regular cells are added to
    it until it is not (or none are left). Cells with expected 0 and observed 0 carry
    no information and are dropped; callers must reject cells with expected 0 but
    observed > 0 before pooling (they would otherwise be diluted).

    Parameters
    ----------
    observed, expected : array_like
        Counts per cell, same shape (any); expected counts must be finite and >= 0.
    min_expected : float > 0
        Smallest expected count a cell may have. 5 is the usual rule of thumb.

    Returns
    -------
    PooledCells
    """
    obs = np.asarray(observed, dtype=np.float64).ravel()
    exp = np.asarray(expected, dtype=np.float64).ravel()
    if obs.shape != exp.shape:
        raise ValueError(f"observed and expected must have the same size, got {obs.size} "
                         f"and {exp.size}")
    if not (np.all(np.isfinite(exp)) and np.all(exp >= 0)):
        raise ValueError("expected counts must be finite and >= 0")
    if not (np.all(np.isfinite(obs)) and np.all(obs >= 0)):
        raise ValueError("observed counts must be finite and >= 0")
    if not min_expected > 0:
        raise ValueError(f"min_expected must be > 0, got {min_expected!r}")

    informative = (exp > 0) | (obs > 0)
    obs, exp = obs[informative], exp[informative]
    order = np.argsort(exp, kind="stable")
    obs, exp = obs[order], exp[order]

    n_low = int(np.count_nonzero(exp < min_expected))
    if n_low == 0:
        return PooledCells(obs, exp, 0)
    # Cells are sorted by expected count, so pooling the first k cells keeps the
    # largest cells intact; grow k until the pooled cell reaches min_expected.
    cumulative = np.cumsum(exp)
    k = max(n_low, int(np.searchsorted(cumulative, min_expected, side="left")) + 1)
    k = min(k, len(exp))
    pooled_obs, pooled_exp = obs[:k].sum(), exp[:k].sum()
    return PooledCells(np.append(obs[k:], pooled_obs), np.append(exp[k:], pooled_exp), k)


def pearson_chi2(observed, expected, min_expected: float = 5.0) -> PearsonResult:
    """Pearson's chi-square test of observed counts against expected counts.

    Cells are pooled first (see ``pool_low_expected``); the statistic is
    ``sum((O - E)^2 / E)`` over the pooled cells with ``cells - 1`` degrees of freedom,
    and the p-value is its upper tail probability ``scipy.stats.chi2.sf``.

    Parameters
    ----------
    observed, expected : array_like
        Counts per cell. For an exact test, expected counts should sum to the same
        total as the observed ones (include a cell for "no outcome" if needed).
    min_expected : float > 0
        Pooling threshold.

    Returns
    -------
    PearsonResult

    Examples
    --------
    >>> r = pearson_chi2([10, 20, 30], [20, 20, 20])
    >>> r.statistic, r.dof, round(r.p_value, 6)   # chi2(2 dof).sf(10) = exp(-5)
    (10.0, 2, 0.006738)
    """
    cells = pool_low_expected(observed, expected, min_expected)
    with np.errstate(divide="ignore", invalid="ignore"):  # E = 0 with O > 0 -> infinite
        terms = (cells.observed - cells.expected) ** 2 / cells.expected
    statistic = float(np.sum(np.where(cells.observed == cells.expected, 0.0, terms)))
    dof = len(cells.observed) - 1
    p_value = float(sps.chi2.sf(statistic, dof)) if dof >= 1 else float("nan")
    return PearsonResult(statistic, dof, p_value, len(cells.observed), cells.pooled_in)


def check_significance(value) -> float:
    """A significance level strictly between 0 and 1."""
    try:
        alpha = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"significance must be a number in (0, 1), got {value!r}") from None
    if not 0.0 < alpha < 1.0:
        raise ValueError(f"significance must be in (0, 1), got {alpha!r}")
    return alpha
