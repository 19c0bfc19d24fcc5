"""Posterior predictive checks per measured series (Gelman et al. 2013, "Bayesian Data
Analysis", 3rd ed., ch. 6: the chi^2 discrepancy and its posterior predictive p-value).

For every measured curve (``Dataset.groups``: one geometry and angle set) and for all rows
together, the discrepancy of data y and parameters theta is

    T(y, theta) = sum_i ((y_i - m_i(theta)) / (s sigma_i))^2

with s the noise scale. The replicated data y_rep = m(theta) + s sigma eps (eps standard
normal) has T(y_rep, theta) = sum eps_i^2, exactly chi^2 with n degrees of freedom whatever
theta is, so the p-value

    p = Pr(T(y_rep, theta) >= T(y, theta) | y) = E_theta[ chi2_n.sf(T(y, theta)) ]

is the posterior mean of the chi^2 survival function: no replication noise, and p-values far
below 1 / draws are resolved (a Rao-Blackwellised estimate of the usual simulation).

A study raises a warning when a check's p is below the Sidak-corrected level
1 - (1 - ALPHA)^(1/k) over its k checks, so a right model raises one (false alarm) in at most
ALPHA of studies (posterior predictive p-values are conservative: under the right model they
crowd toward 0.5, not uniform). A free noise scale absorbs a misfit common to every series;
a series that misfits against the others still fails, and the noise-scale warning covers the
common part.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
from scipy import stats

from bsdflab.fit.data import Dataset

ALPHA = 0.01   # family-wise false-alarm rate of a study's checks


@dataclass(frozen=True)
class SeriesCheck:
    series: str
    rows: int
    p_value: float
    chi2_per_row: float      # posterior median of T(y, theta) / n (1 for a right model)
    flagged: bool

    def to_dict(self) -> dict:
        return asdict(self)


def sidak_level(checks: int, alpha: float = ALPHA) -> float:
    """Per-check level that keeps the family-wise false-alarm rate at ``alpha``."""
    return 1.0 - (1.0 - alpha) ** (1.0 / checks)


def predictive_checks(dataset: Dataset, model_draws: np.ndarray, noise_scale: np.ndarray,
                      alpha: float = ALPHA) -> list[SeriesCheck]:
    """Checks of "all rows" and of each series, from the model values (P, rows) and noise
    scales (P,) of P posterior draws."""
    model_draws = np.atleast_2d(np.asarray(model_draws, float))
    s = np.asarray(noise_scale, float).reshape(-1, 1) * dataset.sigma[None, :]
    z2 = ((dataset.reflectance[None, :] - model_draws) / s) ** 2
    groups = [("all rows", np.arange(len(dataset)))] + dataset.groups()
    level = sidak_level(len(groups), alpha)
    out = []
    for label, idx in groups:
        t = np.sum(z2[:, idx], axis=1)
        t = np.where(np.isfinite(t), t, np.inf)
        p = float(np.mean(stats.chi2.sf(t, len(idx))))
        out.append(SeriesCheck(label, len(idx), p, float(np.median(t)) / len(idx), p < level))
    return out


def normalised_residuals(dataset: Dataset, model_draws: np.ndarray, noise_scale: np.ndarray) -> np.ndarray:
    """(y - median model) / (median s sigma) per row: standard normal for a right model."""
    m = np.median(np.atleast_2d(model_draws), axis=0)
    return (dataset.reflectance - m) / (float(np.median(noise_scale)) * dataset.sigma)
