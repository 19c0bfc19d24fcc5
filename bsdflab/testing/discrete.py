"""Goodness-of-fit test for discrete outcomes, such as which lobe a sampler chose.

Delta lobes have no density, so the direction chi-square test cannot see them; what can
be tested is how often each lobe is chosen. For a smooth dielectric, for example,
reflection must be chosen with the Fresnel reflectance R and transmission with 1 - R.
"""
from __future__ import annotations

from collections.abc import Hashable
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import stats as sps

from bsdflab.testing.directions import positive_int
from bsdflab.testing.stats import check_significance, pearson_chi2, sidak_significance

# Probabilities given by the caller must sum to 1 up to rounding.
PROBABILITY_SUM_TOLERANCE = 1e-6


@dataclass(frozen=True)
class DiscreteChoiceResult:
    """Outcome of ``discrete_choice_chi2``; truthy when the test passed."""

    passed: bool
    p_value: float
    statistic: float                 # Pearson's chi^2 (reported for every method)
    dof: int
    method: str                      # 'exact binomial', 'chi-square' or 'single outcome'
    significance: float              # the Sidak-corrected level p_value is compared with
    counts: dict[Hashable, int]      # observed count per label
    expected: dict[Hashable, float]  # expected count per label
    message: str

    def __bool__(self) -> bool:
        return self.passed


def discrete_choice_chi2(observed_labels, expected_probabilities: dict[Hashable, float],
                         significance: float = 0.01, test_count: int = 1,
                         min_expected: float = 5.0) -> DiscreteChoiceResult:
    """Test that discrete outcomes occur with the expected probabilities.

    With two possible outcomes this is the exact two-sided binomial test
    (``scipy.stats.binomtest``); with more, Pearson's chi-square test with pooling of
    rare outcomes. An outcome that is observed but has no (or zero) expected
    probability fails the test outright.

    Parameters
    ----------
    observed_labels : array_like, shape (N,)
        One label per trial, e.g. ``BSDFSample.lobe``.
    expected_probabilities : dict
        ``{label: probability}``; probabilities in [0, 1] summing to 1. Labels compare
        by value, so ``Lobe.DELTA_REFLECTION`` matches the integer 4.
    significance : float in (0, 1)
        Family-wise significance level. Default 0.01.
    test_count : int
        Number of tests in the family (Sidak correction). Default 1.
    min_expected : float
        Pooling threshold of the chi-square method. Default 5.

    Returns
    -------
    DiscreteChoiceResult

    Examples
    --------
    >>> import numpy as np
    >>> coins = np.random.default_rng(1).random(10_000) < 0.3
    >>> discrete_choice_chi2(coins, {True: 0.3, False: 0.7}).passed
    True
    """
    labels = np.asarray(observed_labels).ravel()
    if labels.size == 0:
        raise ValueError("observed_labels must not be empty")
    probabilities = _probabilities(expected_probabilities)
    alpha = sidak_significance(check_significance(significance),
                               positive_int("test_count", test_count))

    try:
        values, counts = np.unique(labels, return_counts=True)
    except TypeError:
        raise ValueError("observed_labels must be labels of one comparable type") from None
    observed = {_plain(v): int(c) for v, c in zip(values, counts)}
    n = int(labels.size)
    unexpected = {k: c for k, c in observed.items() if probabilities.get(k, 0.0) == 0.0}
    possible = [k for k, p in probabilities.items() if p > 0.0]
    counts_out = {k: observed.get(k, 0) for k in possible} | unexpected
    expected_out = {k: n * probabilities[k] for k in possible} | {k: 0.0 for k in unexpected}

    failures = [f"{_name(k)} observed {c} times but has expected probability 0"
                for k, c in unexpected.items()]
    chi2 = pearson_chi2(list(counts_out.values()), list(expected_out.values()), min_expected)
    if len(possible) == 1:
        method, p_value = "single outcome", 1.0  # any other outcome is caught below
    elif len(possible) == 2:
        method = "exact binomial"
        p_value = float(sps.binomtest(counts_out[possible[0]], n,
                                      probabilities[possible[0]]).pvalue)
    else:
        method, p_value = "chi-square", chi2.p_value
        if chi2.dof < 1:
            failures.append("too few trials: fewer than two outcome groups after pooling")
    statistic = chi2.statistic
    if unexpected:  # an outcome impossible under the hypothesis: certain rejection
        statistic, p_value = float("inf"), 0.0
    passed = not failures and bool(np.isfinite(p_value)) and p_value >= alpha

    lines = [f"discrete choice test ({method}) of {n} trials"]
    lines += [f"  {_name(k)}: observed {counts_out[k]}, expected {expected_out[k]:.1f}"
              for k in counts_out]
    lines.append(f"  chi^2 = {statistic:.3f}, p-value = {p_value:.4g}, "
                 f"significance {significance:g} (Sidak-corrected for {test_count}: {alpha:.4g})")
    lines += [f"  failure: {reason}" for reason in failures]
    lines.append("ACCEPTED" if passed else "REJECTED: the outcome frequencies do not match "
                 "the expected probabilities")
    dof = chi2.dof if method == "chi-square" else len(possible) - 1
    return DiscreteChoiceResult(passed=passed, p_value=p_value, statistic=statistic,
                                dof=dof, method=method, significance=alpha, counts=counts_out,
                                expected=expected_out, message="\n".join(lines))


def _probabilities(value: Any) -> dict[Hashable, float]:
    if not isinstance(value, dict) or not value:
        raise ValueError("expected_probabilities must be a non-empty dict {label: probability}")
    out = {}
    for label, p in value.items():
        try:
            p = float(p)
        except (TypeError, ValueError):
            raise ValueError(f"probability of {label!r} must be a number, got {p!r}") from None
        if not (np.isfinite(p) and 0.0 <= p <= 1.0):
            raise ValueError(f"probability of {label!r} must be in [0, 1], got {p!r}")
        out[_plain(label)] = p
    total = sum(out.values())
    if abs(total - 1.0) > PROBABILITY_SUM_TOLERANCE:
        raise ValueError(f"expected probabilities must sum to 1, got {total:.9g}")
    return out


def _plain(label: Any) -> Any:
    """numpy scalars as Python values, so labels hash and compare by value."""
    return label.item() if isinstance(label, np.generic) else label


def _name(label: Any) -> str:
    return getattr(label, "name", None) or repr(label)
