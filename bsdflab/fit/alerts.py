"""The warnings a study raises: what makes its answer doubtful, said loudly (the CLI prints
them as a block on stderr; summary.json lists them with their codes).

Codes
    PRIOR_BOUND       a parameter's posterior piles at an end of its prior: the data push
                      it past what the prior allows
    DOMAIN_BOUND      ... at an end of the model's domain (a thickness spread of 0): the
                      data are consistent with the limit; a one-sided interval
    PRIOR_CONFLICT    a parameter's posterior median lies in its prior's outer 0.27 % (beyond
                      +-3 sd of a normal prior): the data and the prior disagree
    NOISE_SCALE       a free noise_scale far from 1: the model misfits the data (or the
                      stated sigmas are wrong) by that factor
    NOT_CONVERGED     the run stopped at the step cap, not by the convergence rule
    PREDICTIVE_CHECK  a posterior predictive check failed (bsdflab.fit.checks)
    THICKNESS_MODES   several thickness modes (interference orders): among the MAP starts'
                      optima, or in the draws (nested sampling keeps every mode)
    EMULATOR_ERROR    the full model's emulator misses the direct solves by more than the
                      data's sigma
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from bsdflab.fit.checks import ALPHA
from bsdflab.fit.parameters import parameter

EDGE = 0.02              # "at a bound": within 2 % of the prior's range of it
PILE = 0.10              # ... holding >= 10 % of the draws (a flat posterior holds 2 %)
NOISE_RANGE = (0.5, 2.0)
MODE_LOG_RATIO = float(np.log(100.0))   # another optimum within a factor 100 of the best density
MODE_MIN_MASS = 0.05     # a mode in the draws holds >= 5 % of them
MODE_GAP = 3.0           # ... and is separated from the next by a gap >= 3 sd of its neighbours
THICKNESS_NAMES = ("film_thickness_nm", "platelet_nm")   # the snake model's; a stack's are <layer>_thickness_nm
PRIOR_TAIL = 1e-4        # an unbounded prior's range: its 1e-4 and 1 - 1e-4 quantiles
CONFLICT_TAIL = 0.00135  # prior-data conflict: the posterior median beyond the prior's +-3 sd quantiles


@dataclass(frozen=True)
class Alert:
    code: str
    message: str
    parameter: str | None = None

    def to_dict(self) -> dict:
        return asdict(self)


def thickness_names(names) -> list[str]:
    """The layer thicknesses among ``names``: the snake model's and a stack's layers'."""
    return [n for n in names if n in THICKNESS_NAMES or n.endswith("_thickness_nm")]


def _domain(name: str, domains: dict | None):
    """The parameter's domain: from ``domains`` (a stack's layer and instrument parameters),
    else the snake model's table."""
    return domains[name] if domains is not None and name in domains else parameter(name)


def prior_range(name: str, prior, domains: dict | None = None) -> tuple[float, float, float]:
    """(lo, hi, width): the finite ends of the prior's support within the model's domain
    (+-inf where open) and the width of its central mass."""
    p = _domain(name, domains)
    lo, hi = prior.support()
    lo, hi = max(lo, p.lo), min(hi, p.hi)
    wlo, whi = float(prior.ppf(PRIOR_TAIL)), float(prior.ppf(1 - PRIOR_TAIL))
    return lo, hi, max(min(whi, hi) - max(wlo, lo), 0.0)


def bound_alerts(names, draws: np.ndarray, priors: dict, domains: dict | None = None) -> list[Alert]:
    out = []
    for j, name in enumerate(names):
        lo, hi, width = prior_range(name, priors[name], domains)
        if not width > 0:
            continue
        x = draws[:, j]
        p = _domain(name, domains)
        for end, side, near, limit in ((lo, "lower", x <= lo + EDGE * width, p.lo),
                                       (hi, "upper", x >= hi - EDGE * width, p.hi)):
            if not (np.isfinite(end) and np.mean(near) >= PILE):
                continue
            share = f"{name}: {np.mean(near):.0%} of the posterior lies within {EDGE:.0%} of the "
            if end == limit:   # the model's own limit (a spread of 0, an albedo of 1): no prior to widen
                out.append(Alert("DOMAIN_BOUND", share + f"model's {side} limit {end:g}: the data are consistent "
                                 "with the limit (quote a one-sided interval, or fix it there)", name))
            else:
                out.append(Alert("PRIOR_BOUND", share + f"prior's {side} bound {end:g} ({priors[name].describe()}): "
                                 "the data push it beyond the prior; widen the prior or question the model", name))
    return out


def conflict_alerts(names, draws: np.ndarray, priors: dict) -> list[Alert]:
    """Posterior medians in the prior's far tails (uniform priors have none: their piling is
    PRIOR_BOUND's)."""
    out = []
    for j, name in enumerate(names):
        prior = priors[name]
        if prior.kind == "uniform":
            continue
        m = float(np.median(draws[:, j]))
        u = float(prior.dist.cdf(m))
        if u < CONFLICT_TAIL or u > 1 - CONFLICT_TAIL:
            out.append(Alert("PRIOR_CONFLICT", f"{name}: the posterior median {m:.5g} lies at prior quantile "
                             f"{u:.2g} ({prior.describe()}): the data and the prior disagree (a wrong prior, or the "
                             "model compensates for something it lacks)", name))
    return out


def noise_alert(names, draws: np.ndarray) -> list[Alert]:
    if "noise_scale" not in names:
        return []
    s = float(np.median(draws[:, list(names).index("noise_scale")]))
    if NOISE_RANGE[0] <= s <= NOISE_RANGE[1]:
        return []
    what = ("the model misfits the data, or the stated sigmas are too small," if s > 1 else
            "the stated sigmas are too large")
    return [Alert("NOISE_SCALE", f"noise_scale = {s:.3g} (outside {NOISE_RANGE[0]:g}-{NOISE_RANGE[1]:g}): {what} "
                  f"by a factor {max(s, 1 / s):.3g}; the parameter intervals are scaled by it", "noise_scale")]


def draw_modes(x: np.ndarray) -> list[tuple[float, float]]:
    """(mean, mass) of the well-separated clusters of 1-D draws: split, recursively, at the
    widest gap that exceeds MODE_GAP x the larger sd of the MODE_MIN_MASS share of draws on
    either side of it (its neighbourhood), both sides holding >= MODE_MIN_MASS of all draws.
    In a unimodal sample a gap is a small fraction of its neighbours' spread; interference
    orders are separated by many sds of each mode."""
    x = np.sort(np.asarray(x, float)[np.isfinite(x)])
    total = len(x)
    k = int(np.ceil(MODE_MIN_MASS * total))

    def window_sd(c1, c2, a, b):
        n = b - a
        return np.sqrt(np.maximum((c2[b] - c2[a]) / n - ((c1[b] - c1[a]) / n) ** 2, 0))

    def split(v: np.ndarray) -> list[np.ndarray]:
        n = len(v)
        if n < 2 * k or k < 2:
            return [v]
        c1, c2 = np.concatenate([[0.0], np.cumsum(v)]), np.concatenate([[0.0], np.cumsum(v * v)])
        i = np.arange(k - 1, n - k)                       # split after index i
        spread = np.maximum(window_sd(c1, c2, i + 1 - k, i + 1), window_sd(c1, c2, i + 1, i + 1 + k))
        gap = v[i + 1] - v[i]
        ok = gap > MODE_GAP * spread
        if not np.any(ok):
            return [v]
        j = i[ok][np.argmax(gap[ok])]
        return split(v[:j + 1]) + split(v[j + 1:])

    return [(float(np.mean(c)), len(c) / total) for c in split(x)] if total else []


def mode_alerts(names, draws: np.ndarray, optima) -> list[Alert]:
    """Several thickness modes: in the draws, or among the MAP optima (x, log p) within a
    factor exp(MODE_LOG_RATIO) of the best density and further apart than 5 posterior sds."""
    out = []
    for name in thickness_names(names):
        j = list(names).index(name)
        modes = draw_modes(draws[:, j])
        if len(modes) > 1:
            out.append(Alert("THICKNESS_MODES", f"{name}: the posterior has {len(modes)} separate modes ("
                             + ", ".join(f"{m:.1f} nm: {w:.0%}" for m, w in modes)
                             + "): interference orders the data do not tell apart; report them separately", name))
            continue
        if not optima:
            continue
        sd = float(np.std(draws[:, j])) or 1.0
        best = max(lp for _, lp in optima)
        found: list[tuple[float, float]] = []
        for x, lp in sorted(optima, key=lambda o: -o[1]):
            if lp < best - MODE_LOG_RATIO:
                continue
            if all(abs(x[j] - d) > 5 * sd for d, _ in found):
                found.append((float(x[j]), best - lp))
        if len(found) > 1:
            out.append(Alert("THICKNESS_MODES", f"{name}: the MAP starts found {len(found)} optima of similar "
                             "density (" + ", ".join(f"{d:.1f} nm: ln p {-dl:+.2f}" for d, dl in found)
                             + "); the sampler explored only the best (interference-order ambiguity): run "
                             "[sampler] kind = \"nested\" or narrow the thickness prior", name))
    return out


def check_alert(checks, figures: bool = True) -> list[Alert]:
    """One PREDICTIVE_CHECK warning naming the failed checks (bsdflab.fit.checks); it points
    at residuals.png when the study draws figures, else at summary.json."""
    failed = [c for c in checks if c.flagged]
    if not failed:
        return []
    return [Alert("PREDICTIVE_CHECK", f"{len(failed)} of {len(checks)} posterior predictive checks fail "
                  f"(family-wise alpha {ALPHA:g}): " + "; ".join(
                      f"{c.series}: p = {c.p_value:.2g}, chi2/n = {c.chi2_per_row:.2f}" for c in failed[:6])
                  + ("; ..." if len(failed) > 6 else "") + " -- the model does not describe these data "
                  + ("(see residuals.png)" if figures else "(see predictive_checks in summary.json)"))]


def fit_alerts(run, draws: np.ndarray, priors: dict, checks, domains: dict | None = None,
               figures: bool = True) -> list[Alert]:
    """Every warning a fit's run and checks raise, in the order a reader should act on them
    (``domains``: parameters beyond the snake model's table, as a structure fit's)."""
    alerts = [] if run.converged else [Alert("NOT_CONVERGED", run.stop_reason)]
    alerts += bound_alerts(run.names, draws, priors, domains)
    alerts += conflict_alerts(run.names, draws, priors)
    alerts += noise_alert(run.names, draws)
    alerts += check_alert(checks, figures)
    alerts += mode_alerts(run.names, draws, run.map.optima)
    return alerts


def emulator_alert(forward: dict) -> list[Alert]:
    e = forward.get("emulator_max_error_sigma")
    if e is None or e <= 1.0:
        return []
    return [Alert("EMULATOR_ERROR", f"the emulator misses the direct solves by up to {e:.2g} sigma: raise "
                  "[model] emulator_nodes or narrow the priors")]


def render_block(alerts: list[Alert]) -> str:
    """The warnings as one block for stderr."""
    if not alerts:
        return ""
    bar = "!" * 78
    lines = [bar, f"!! bsdflab fit: {len(alerts)} warning(s): this study's answer is doubtful", bar]
    lines += [f"[{a.code}] {a.message}" for a in alerts]
    lines.append(bar)
    return "\n".join(lines) + "\n"
