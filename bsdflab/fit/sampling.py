"""MAP initialisation (scipy.optimize) and emcee sampling with an autocorrelation stop.

Stop rule (emcee's documented recipe): every ``check_every`` steps estimate the integrated
autocorrelation time tau of every parameter; stop when the chain is longer than
``tau_multiple`` x max tau AND every tau changed by < 1 % since the last check, or at
``max_steps`` (the step cap). ``RunResult.stop_reason`` says which happened.
Burn-in = 2 max tau, thinning = max(1, min tau / 2) for the posterior draws.

Moves: 80 % emcee's differential-evolution move (DEMove: ter Braak 2006, with Nelson et al.
2014's random gamma), 20 % the stretch move (Goodman & Weare 2010), not the stretch move alone.
Each keeps the posterior invariant (DEMove's proposal is symmetric; the stretch move carries
its z^(d-1) factor), so the target is unchanged;
what changes is the mixing. A free film index makes a thin, curved thickness-index ridge
(n d fixed to the fringe positions, only the angle dependence separating n from d; correlation
-0.995): there the stretch move's tau was ~80 steps (12 walkers, 5 parameters), its 500-step
runs reported sds 0.85x the true ones (mean z^2 1.5-1.9 in SBC), and its tau estimate on such
short runs (~36) hid it. The DE proposals step along the ensemble's own differences, i.e.
along the ridge: tau ~21 on the same posterior, sds equal to nested sampling's and a long
stretch run's (docs/fit.md, "Structures and instruments").
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
from scipy import optimize

from bsdflab.fit.config import SamplerSettings
from bsdflab.fit.posterior import LogPosterior
from bsdflab.util.extras import require
from bsdflab.util.progress import report_progress, stop_if_cancelled

emcee = require("emcee", "fit")

TAU_CHANGE = 0.01
FD_STEP = 1e-6   # finite-difference step of the MAP gradient, in prior sds
HESS_STEP = 1e-4   # ... of the Laplace approximation's Hessian
POOL_CHUNK = 64     # prior draws of the MAP pool evaluated between cancel checks
MAP_ITERATIONS = 500   # L-BFGS-B iterations per MAP start


@dataclass
class MapResult:
    x: np.ndarray
    log_posterior: float
    starts: int
    evaluations: int
    optima: list[tuple[np.ndarray, float]] = field(default_factory=list)   # every start's (x, log p)


@dataclass
class RunResult:
    names: tuple[str, ...]
    chain: np.ndarray            # (steps, walkers, ndim), whole run
    log_prob: np.ndarray         # (steps, walkers)
    acceptance: np.ndarray       # (walkers,)
    tau: np.ndarray              # (ndim,) at the end
    tau_history: list[tuple[int, np.ndarray]]
    converged: bool
    stop_reason: str
    seconds: float
    evaluations: int
    map: MapResult
    sampler: emcee.EnsembleSampler = field(repr=False)

    @property
    def steps(self) -> int:
        return self.chain.shape[0]

    @property
    def burn(self) -> int:
        return min(int(np.ceil(2.0 * np.max(self.tau))), self.steps - 2)

    @property
    def thin(self) -> int:
        return max(1, int(0.5 * np.min(self.tau)))

    def draws(self) -> np.ndarray:
        """Post-burn-in, thinned draws, flattened over walkers: (n, ndim)."""
        return self.chain[self.burn::self.thin].reshape(-1, self.chain.shape[2])

    def ess_tau(self) -> np.ndarray:
        """Effective sample size per parameter after burn-in: (steps - burn) walkers / tau."""
        return (self.steps - self.burn) * self.chain.shape[1] / self.tau


def find_map(logpost: LogPosterior, starts: int, rng: np.random.Generator, progress: bool = False) -> MapResult:
    """Best of ``starts`` L-BFGS-B runs from the most probable of many prior draws
    (thin-film likelihoods have a mode per interference order: one local start is not
    enough). Coordinates are scaled by the prior sd; the gradient is a central difference
    whose 2 ndim + 1 points go to the forward model as one batch."""
    before = logpost.evaluations
    pool = logpost.sample_prior(max(256, 32 * starts), rng)
    lp = np.empty(len(pool))
    for i in range(0, len(pool), POOL_CHUNK):   # a cancel is honoured between chunks
        stop_if_cancelled("the MAP search")
        lp[i:i + POOL_CHUNK] = logpost(pool[i:i + POOL_CHUNK])
    order = np.argsort(-np.where(np.isfinite(lp), lp, -np.inf))[:starts]
    scale = np.array([logpost.config.priors[n].dist.std() for n in logpost.free])
    bounds = []
    for n, sc in zip(logpost.free, scale):
        lo, hi = logpost.config.priors[n].support()
        # open support ends (a log-normal's 0) are kept a whisker away
        bounds.append((lo / sc + FD_STEP * 2 if np.isfinite(lo) else None,
                       hi / sc - FD_STEP * 2 if np.isfinite(hi) else None))
    eye = np.eye(len(scale)) * FD_STEP

    def value_and_gradient(z):
        stop_if_cancelled("the MAP search")   # a start is up to 500 iterations: check each one
        pts = np.vstack([z, z + eye, z - eye]) * scale
        v = -logpost(pts)
        f0, fp, fm = v[0], v[1:1 + len(z)], v[1 + len(z):]
        if not np.isfinite(f0):
            return 1e300, np.zeros_like(z)
        fp = np.where(np.isfinite(fp), fp, f0)
        fm = np.where(np.isfinite(fm), fm, f0)
        return f0, (fp - fm) / (2 * FD_STEP)

    best, optima = None, []
    if progress:
        from tqdm import tqdm

        order = tqdm(order, desc="MAP starts", unit="start", leave=False)
    for done, i in enumerate(order):
        report_progress("MAP", done / starts)
        res = optimize.minimize(value_and_gradient, pool[i] / scale, jac=True, method="L-BFGS-B",
                                bounds=bounds, options={"maxiter": MAP_ITERATIONS, "ftol": 1e-12, "gtol": 1e-8})
        optima.append((res.x * scale, float(-res.fun)))
        if best is None or res.fun < best.fun:
            best = res
    x = best.x * scale
    return MapResult(x, float(-best.fun), starts, logpost.evaluations - before, optima)


def laplace_covariance(logpost: LogPosterior, centre: np.ndarray) -> np.ndarray | None:
    """The Laplace approximation's covariance at the MAP, (-Hessian of log p)^-1, from central
    differences (step HESS_STEP prior sds, the 4 ndim^2 + 1 points as one batch); the
    stencil's centre kept 2.5 steps inside the prior's support (a MAP on a bound): with
    exactly 2 the outermost point rounded to just outside the support for a quarter to a half
    of the MAPs on a bound, and the start fell back to the tiny ball. None where the Hessian
    is not finite or -H not positive definite."""
    scale = np.array([logpost.config.priors[n].dist.std() for n in logpost.free])
    lo, hi = np.array([logpost.config.priors[n].support() for n in logpost.free]).T / scale
    h, nd = HESS_STEP, len(centre)
    c = np.clip(centre / scale, lo + 2.5 * h, hi - 2.5 * h)
    e = np.eye(nd) * h
    pts = [c] + [c + s1 * e[a] + s2 * e[b] for a in range(nd) for b in range(nd) for s1 in (1, -1) for s2 in (1, -1)]
    v = logpost(np.array(pts) * scale)
    if not np.all(np.isfinite(v)):
        return None
    q = v[1:].reshape(nd, nd, 4)
    hess = (q[..., 0] - q[..., 1] - q[..., 2] + q[..., 3]) / (4 * h * h)
    try:
        cov = np.linalg.inv(-0.5 * (hess + hess.T))
        np.linalg.cholesky(cov)
    except np.linalg.LinAlgError:
        return None
    return cov * np.outer(scale, scale)


def initial_ball(logpost: LogPosterior, centre: np.ndarray, walkers: int,
                 rng: np.random.Generator) -> np.ndarray:
    """Walkers drawn from the Laplace approximation at the MAP (N(MAP, (-H)^-1), redrawn
    outside the support), all with a finite posterior; a tiny Gaussian ball (1e-4 prior sd)
    where the Hessian is unusable. Why not always the tiny ball: the ensemble needs ~100 steps
    to expand from it (measured on the film thickness-index ridge), longer than the burn-in
    of 2 tau (~40 steps), so the kept draws began too narrow."""
    cov = laplace_covariance(logpost, centre)
    if cov is not None:
        chol = np.linalg.cholesky(cov)
        p0 = centre + rng.standard_normal((walkers, len(centre))) @ chol.T
        for _ in range(100):
            bad = ~np.isfinite(logpost(p0))
            if not np.any(bad):
                return p0
            p0[bad] = centre + rng.standard_normal((int(bad.sum()), len(centre))) @ chol.T
    scale = 1e-4 * np.array([logpost.config.priors[n].dist.std() for n in logpost.free])
    p0 = centre + scale * rng.standard_normal((walkers, len(centre)))
    for _ in range(100):
        bad = ~np.isfinite(logpost(p0))
        if not np.any(bad):
            return p0
        p0[bad] = centre + scale * rng.standard_normal((int(bad.sum()), len(centre)))
    raise ValueError("could not place the walkers around the MAP inside the prior's support")


def stop_reason(steps: int, tau: np.ndarray, history: list[tuple[int, np.ndarray]], converged: bool,
                settings: SamplerSettings) -> str:
    """Which criterion ended the run, stated as it is: the rule has two parts (length and
    stability), so a capped run may pass the length test and fail the stability one."""
    ratio = steps / np.max(tau)
    k = settings.tau_multiple
    if converged:
        return (f"converged: N / max tau = {ratio:.1f} > {k:g} (N = {steps}, max tau {np.max(tau):.1f}) "
                f"and tau stable to {TAU_CHANGE:.0%} between checks")
    failed = []
    if not np.all(np.isfinite(tau)):
        failed.append("tau undefined for some parameter")
    elif not ratio > k:
        failed.append(f"N / max tau = {ratio:.1f} {'<' if ratio < k else '<='} {k:g}")
    else:
        failed.append(f"N / max tau = {ratio:.1f} > {k:g} passed")
    if len(history) >= 2 and np.all(np.isfinite(history[-1][1])) and np.all(np.isfinite(history[-2][1])):
        old, new = history[-2][1], history[-1][1]
        change = float(np.max(np.abs(old - new) / new))
        failed.append(f"tau changed by {change:.1%} since the last check ("
                      + ("stable" if change < TAU_CHANGE else f"not stable to {TAU_CHANGE:.0%}") + ")")
    else:
        failed.append("tau not yet checked twice (stability unknown)")
    return f"step cap {settings.max_steps} reached; " + "; ".join(failed) + " (not converged)"


def moves():
    """The proposal mixture (see the module docstring)."""
    return [(emcee.moves.DEMove(), 0.8), (emcee.moves.StretchMove(), 0.2)]


class _InterruptLater:
    """The log posterior as emcee sees it. A Ctrl-C that lands inside it is held until the
    step ends, then raised by ``run_sampler``'s loop: emcee's own wrapper prints a traceback
    for anything the likelihood raises, which would stand above the CLI's one-line message.
    The step's proposals get -inf (rejected) and the chain is thrown away with the raise."""

    def __init__(self, logpost: LogPosterior):
        self.logpost, self.interrupted = logpost, False

    def __call__(self, x: np.ndarray) -> np.ndarray:
        try:
            return self.logpost(x)
        except KeyboardInterrupt:
            self.interrupted = True
            return np.full(len(x), -np.inf)


def run_sampler(logpost: LogPosterior, settings: SamplerSettings, progress: bool = True) -> RunResult:
    rng = np.random.default_rng(settings.seed)
    t0 = time.perf_counter()
    map_result = find_map(logpost, settings.map_starts, rng, progress)
    p0 = initial_ball(logpost, map_result.x, settings.walkers, rng)
    before = logpost.evaluations
    target = _InterruptLater(logpost)
    sampler = emcee.EnsembleSampler(settings.walkers, logpost.ndim, target, moves=moves(), vectorize=True)
    # emcee's moves draw from its own RandomState; seed it from our generator for repeatability
    sampler.random_state = np.random.RandomState(int(rng.integers(2**32))).get_state()
    history: list[tuple[int, np.ndarray]] = []
    converged, old_tau = False, None
    for _ in sampler.sample(p0, iterations=settings.max_steps, progress=progress):
        if target.interrupted:
            raise KeyboardInterrupt
        n = sampler.iteration
        report_progress("sampling", n / settings.max_steps)   # the cap: converging earlier jumps to the end
        stop_if_cancelled("sampling")
        if n % settings.check_every:
            continue
        tau = sampler.get_autocorr_time(tol=0)
        history.append((n, tau))
        if (old_tau is not None and np.all(np.isfinite(tau)) and np.all(n > settings.tau_multiple * tau)
                and np.all(np.abs(old_tau - tau) < TAU_CHANGE * tau)):
            converged = True
            break
        old_tau = tau
    seconds = time.perf_counter() - t0
    tau = sampler.get_autocorr_time(tol=0)
    if not history or history[-1][0] != sampler.iteration:
        history.append((sampler.iteration, tau))
    reason = stop_reason(sampler.iteration, tau, history, converged, settings)
    return RunResult(logpost.free, sampler.get_chain(), sampler.get_log_prob(), sampler.acceptance_fraction,
                     tau, history, converged, reason, seconds, logpost.evaluations - before, map_result, sampler)
