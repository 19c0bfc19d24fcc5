"""Nested sampling (dynesty; Skilling 2006, Speagle 2020) for multi-modal posteriors and
model evidence.

Thin-film likelihoods have one mode per interference order: emcee's ensemble, started in
one mode, stays there (its stretch move cannot cross a valley of low probability), so it
reports a posterior that misses the other orders. Nested sampling shrinks a cloud of live
points drawn from the prior toward higher likelihood and keeps every mode that holds live
points, and it estimates the evidence Z = integral of L x prior, the number that compares
models (no film / one film / a platelet stack): the Bayes factor of two models is the
ratio of their Z.

The prior enters through its quantile function (``Prior.ppf``, the unit cube -> the
parameter), the likelihood is ``LogPosterior.log_likelihood``. dynesty calls it one point at a
time, so this suits the smooth C++ model and the full model's emulator (both fast per
point), not direct solves.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from bsdflab.fit.posterior import LogPosterior
from bsdflab.fit.sampling import MapResult
from bsdflab.util.extras import require
from bsdflab.util.progress import stop_if_cancelled

dynesty = require("dynesty", "fit")

FLOOR = -1e300   # dynesty wants finite log-likelihoods: outside the model's domain


@dataclass
class NestedResult:
    names: tuple[str, ...]
    samples: np.ndarray          # (n, ndim) equally weighted posterior draws
    log_evidence: float          # ln Z
    log_evidence_error: float    # dynesty's estimate of the standard error of ln Z
    evaluations: int
    seconds: float
    results: object = field(repr=False)   # dynesty's Results
    dlogz: float = 0.1
    map: MapResult | None = None          # the draw of highest posterior density

    converged = True   # dynesty stops only by its dlogz rule (no iteration cap is set)

    def draws(self) -> np.ndarray:
        return self.samples

    @property
    def iterations(self) -> int:
        return int(self.results.niter)

    @property
    def ess_kish(self) -> float:
        """Kish's effective sample size of the importance weights, (sum w)^2 / sum w^2."""
        w = np.exp(self.results.logwt - np.max(self.results.logwt))
        return float(np.sum(w) ** 2 / np.sum(w * w))

    @property
    def stop_reason(self) -> str:
        return (f"nested sampling: the live points' remaining evidence changes ln Z by < dlogz = {self.dlogz:g} "
                f"after {self.iterations} iterations (ln Z = {self.log_evidence:.3f} +- {self.log_evidence_error:.3f})")


def run_nested(logpost: LogPosterior, live_points: int = 200, seed: int = 0, dlogz: float = 0.1,
               sample: str = "rwalk", bound: str = "multi", progress: bool = False) -> NestedResult:
    """Static nested sampling of ``logpost``'s posterior.

    Parameters
    ----------
    live_points : int >= 2 ndim + 2
        More live points resolve more (and smaller) modes and lower the evidence's error
        (~ sqrt(H / live_points), H the information in nats).
    seed : int
        Seeds dynesty's generator (repeatable runs).
    dlogz : float > 0
        Stop when the remaining prior volume could change ln Z by less than this.
    sample, bound : str
        dynesty's proposal ("rwalk", "unif", "slice", ...) and bounding ("multi": several
        ellipsoids, which is what separates modes).
    progress : bool
        dynesty's progress bar (tqdm) on stderr.
    """
    ndim = logpost.ndim
    if not isinstance(live_points, (int, np.integer)) or live_points < 2 * ndim + 2:
        raise ValueError(f"live_points must be an integer >= {2 * ndim + 2} (2 x free parameters + 2), "
                         f"got {live_points!r}")
    if not dlogz > 0:
        raise ValueError(f"dlogz must be > 0, got {dlogz!r}")
    priors = [logpost.config.priors[n] for n in logpost.free]

    def transform(u):
        return np.array([p.ppf(x) for p, x in zip(priors, u)], dtype=float)

    def loglike(x):
        stop_if_cancelled("nested sampling")
        v = float(logpost.log_likelihood(np.asarray(x)[None, :])[0])
        return v if np.isfinite(v) else FLOOR

    before = logpost.evaluations
    t0 = time.perf_counter()
    sampler = dynesty.NestedSampler(loglike, transform, ndim, nlive=int(live_points), bound=bound,
                                    sample=sample, rstate=np.random.default_rng(seed))
    sampler.run_nested(dlogz=dlogz, print_progress=progress)
    res = sampler.results
    draws = res.samples_equal(rstate=np.random.default_rng(seed + 1))
    # the highest-posterior point among the weighted samples (ln L + ln prior)
    lp = res.logl + logpost.log_prior(res.samples)
    k = int(np.argmax(np.where(np.isfinite(lp), lp, -np.inf)))
    best = MapResult(np.asarray(res.samples[k], float), float(lp[k]), 0, 0)
    return NestedResult(logpost.free, draws, float(res.logz[-1]), float(res.logzerr[-1]),
                        logpost.evaluations - before, time.perf_counter() - t0, res, float(dlogz), best)
