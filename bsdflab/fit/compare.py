"""Model comparison by Pareto-smoothed importance-sampling leave-one-out cross-validation
(PSIS-LOO; Vehtari, Gelman & Gabry 2017, as ArviZ computes it), beside the evidence of
nested sampling (bsdflab.fit.nested): the evidence asks how well the prior predicted the
data, LOO how well the fitted model predicts a measurement it did not see.
"""
from __future__ import annotations

import numpy as np

from bsdflab.fit.diagnostics import arviz
from bsdflab.fit.posterior import LogPosterior


def loo_data(logpost: LogPosterior, draws: np.ndarray):
    """ArviZ InferenceData (one chain) of posterior ``draws`` (n, ndim) with the pointwise
    log likelihood (n, rows) that ``arviz.loo`` / ``arviz.compare`` read."""
    az = arviz()
    draws = np.atleast_2d(np.asarray(draws, float))
    ll = logpost.pointwise_log_likelihood(draws)
    if not np.all(np.isfinite(ll)):
        raise ValueError("a posterior draw lies outside the model's domain (non-finite log likelihood)")
    return az.from_dict(posterior={n: draws[None, :, j] for j, n in enumerate(logpost.free)},
                        log_likelihood={"reflectance": ll[None]})


def loo_compare(fits: dict[str, tuple[LogPosterior, np.ndarray]]):
    """``arviz.compare`` (PSIS-LOO, elpd on the log scale) of named (posterior, draws) pairs:
    a DataFrame ranked best first, with elpd_diff and its standard error dse."""
    az = arviz()
    return az.compare({name: loo_data(lp, d) for name, (lp, d) in fits.items()}, ic="loo")
