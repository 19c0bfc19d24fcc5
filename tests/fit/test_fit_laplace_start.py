"""The walkers' start (bsdflab/fit/sampling.py): the Laplace approximation at the MAP on an
analytic Gaussian log-posterior (exact for central differences up to round-off), at a MAP on
every bound of the prior box (where a stencil 2 steps inside the support rounded outside it
for a quarter to a half of such MAPs and the start fell back silently to the 1e-4 ball), and
None for a saddle."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from bsdflab.fit import sampling
from bsdflab.fit.priors import Prior

SD = np.array([4.3, 0.0075, 0.02, 0.002, 3.0])  # the film ridge's scales (thickness nm, index, ...)
CORR = np.eye(5)
CORR[0, 1] = CORR[1, 0] = -0.995
CORR[2, 3] = CORR[3, 2] = -0.84
COV = CORR * np.outer(SD, SD)
MU = np.array([900.0, 1.83, 0.85, 0.01, 15.0])
PRIORS = {
    "t": {"prior": "uniform", "low": 850.0, "high": 950.0},
    "n": {"prior": "uniform", "low": 1.75, "high": 1.9},
    "s": {"prior": "uniform", "low": 0.7, "high": 1.0},
    "b": {"prior": "normal", "mean": 0.01, "sd": 0.005},
    "w": {"prior": "uniform", "low": 5.0, "high": 25.0},
}


class GaussianPosterior:
    """A log-posterior with the interface the sampler reads (free, config.priors, batched
    calls): the priors' log-density plus a Gaussian log-likelihood."""

    def __init__(self, mu, cov, precision_sign=1.0):
        self.free = tuple(PRIORS)
        self.config = SimpleNamespace(priors={n: Prior.make(n, s) for n, s in PRIORS.items()})
        self.mu, self.prec = mu, precision_sign * np.linalg.inv(cov)
        self.evaluations = 0

    def __call__(self, x):
        x = np.atleast_2d(x)
        lp = sum(self.config.priors[n].logpdf(x[:, i]) for i, n in enumerate(self.free))
        d = x - self.mu
        return np.where(np.isfinite(lp), lp - 0.5 * np.einsum("pi,ij,pj->p", d, self.prec, d), -np.inf)


def test_gaussian_covariance_is_recovered():
    cov = sampling.laplace_covariance(GaussianPosterior(MU, COV), MU)
    assert cov is not None
    # the posterior's precision: the likelihood's plus the normal prior's on "b"
    prec = np.linalg.inv(COV)
    prec[3, 3] += 1.0 / PRIORS["b"]["sd"] ** 2
    np.testing.assert_allclose(cov, np.linalg.inv(prec), rtol=1e-4, atol=0)


@pytest.mark.parametrize("index", [0, 1, 2, 4])
@pytest.mark.parametrize("end", [0, 1])
def test_a_map_on_a_bound_keeps_the_laplace_start(index, end):
    name = tuple(PRIORS)[index]
    centre = MU.copy()
    centre[index] = (PRIORS[name]["low"], PRIORS[name]["high"])[end]
    cov = sampling.laplace_covariance(GaussianPosterior(centre, COV), centre)
    assert cov is not None, f"fell back to the tiny ball with {name} on its {('lower', 'upper')[end]} bound"
    p0 = sampling.initial_ball(GaussianPosterior(centre, COV), centre, 12, np.random.default_rng(0))
    assert np.all(np.isfinite(GaussianPosterior(centre, COV)(p0)))
    assert np.std(p0[:, 1]) > 0.1 * SD[1]  # the Laplace spread, not the 1e-4 ball


def test_a_saddle_gives_none():
    assert sampling.laplace_covariance(GaussianPosterior(MU, COV, precision_sign=-1.0), MU) is None
