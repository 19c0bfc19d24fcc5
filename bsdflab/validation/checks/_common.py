"""Check bodies shared by several families: chi-square, white furnace, reciprocity, the
Mitsuba query-by-query comparison, and z-agreement of estimates with a reference."""
from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
from scipy import stats

from bsdflab.lobes import Lobe
from bsdflab.testing import albedo_sampled, albedo_uniform, bsdf_chi2, spherical_directions
from bsdflab.validation.figures import new_figure
from bsdflab.validation.registry import Context, Outcome

SIGNIFICANCE = 0.01  # family-wise false-alarm rate of every statistical check

CHI2_TOLERANCE = ("p-value of Pearson's chi-square (histogram of sample() vs pdf() integrated "
                  "over each cell, low cells pooled) at least the Sidak-corrected level "
                  f"1 - (1 - {SIGNIFICANCE})^(1/m) over the m incident angles: a correct sampler "
                  f"fails with probability {SIGNIFICANCE}")
FURNACE_TOLERANCE = ("|albedo_sampled - albedo_uniform| and (albedo - expected) within z sigma, "
                     "sigma the two estimators' standard errors combined, z the two-sided normal "
                     f"quantile Sidak-corrected at {SIGNIFICANCE} over angles x channels x 2")


def z_limit(n: int, alpha: float = SIGNIFICANCE) -> float:
    """Two-sided normal quantile at the Sidak-corrected level for n comparisons."""
    return float(stats.norm.isf((1.0 - (1.0 - alpha) ** (1.0 / max(int(n), 1))) / 2.0))


def chi2_outcome(ctx: Context, angles_deg, *, lobes=Lobe.ALL, res=31, quadrature_order=5) -> Outcome:
    """bsdf_chi2 at each incident angle (> 90 deg: from below); the figure shows the
    histogram and the integrated pdf of the angle with the smallest p-value."""
    tests = []
    for k, theta in enumerate(angles_deg):
        wi = spherical_directions(np.radians(theta), 0.0)
        t = bsdf_chi2(ctx.model, wi, lobes=lobes, sample_count=int(ctx.effort["samples"]),
                      test_count=len(angles_deg), seed=ctx.seed + k, res=res,
                      significance=SIGNIFICANCE, quadrature_order=quadrature_order)
        t.run()
        tests.append((theta, t))
    theta, worst = min(tests, key=lambda p: (p[1].passed, p[1].p_value))
    with tempfile.TemporaryDirectory() as tmp:
        png = worst.plot(Path(tmp) / "chi2.png")
        ctx.png(png, f"chi-square at theta_i = {theta:g} deg (smallest p-value): histogram of "
                     "sample() | pdf() integrated per cell | difference")
    return Outcome(all(t.passed for _, t in tests), worst.p_value, worst.significance_per_test, ">=",
                   worst.message.splitlines()[-1],
                   {"p_values": {f"{a:g} deg": t.p_value for a, t in tests}})


def furnace_outcome(ctx: Context, angles_deg, expected: float | None, *, wavelengths=(550.0,),
                    uniform_offset=None) -> Outcome:
    """White furnace: albedo by uniform eval and by mean sample weight at each angle; they
    must agree, and equal ``expected`` (or be <= 1 when None). ``uniform_offset(wi)`` adds
    what uniform sampling cannot see (a delta lobe's exact reflectance). Figure: albedo vs
    angle."""
    from dataclasses import replace

    n = int(ctx.effort["samples"])
    rows = []
    for k, theta in enumerate(angles_deg):
        wi = spherical_directions(np.radians(theta), 0.0)
        u = albedo_uniform(ctx.model, wi, n=n, seed=ctx.seed + 2 * k, wavelengths=list(wavelengths))
        if uniform_offset is not None:
            u = replace(u, mean=u.mean + np.asarray(uniform_offset(wi)).ravel())
        s = albedo_sampled(ctx.model, wi, n=n, seed=ctx.seed + 2 * k + 1, wavelengths=list(wavelengths))
        rows.append((theta, u, s))
    z = z_limit(2 * len(rows) * len(wavelengths))
    worst = 0.0
    for _, u, s in rows:
        worst = max(worst, _z(np.abs(u.mean - s.mean), np.hypot(u.stderr, s.stderr)))
        if expected is not None:
            worst = max(worst, _z(np.abs(s.mean - expected), s.stderr), _z(np.abs(u.mean - expected), u.stderr))
        else:  # <= 1: only an excess counts
            worst = max(worst, _z(s.mean - 1.0, s.stderr))
    fig, ax = new_figure(6.5, 3.0)
    t = [r[0] for r in rows]
    for label, idx, fmt in (("uniform eval", 1, "o"), ("mean sample weight", 2, "s")):
        m = np.array([r[idx].mean[0] for r in rows])
        e = np.array([r[idx].stderr[0] for r in rows])
        ax.errorbar(t, m, yerr=z * e, fmt=fmt, capsize=3, label=f"{label} (+- {z:.1f} se)")
    ax.axhline(1.0 if expected is None else expected, color="k", lw=0.8, ls="--",
               label="expected" if expected is not None else "1 (upper bound)")
    ax.set_xlabel("theta_i (deg)")
    ax.set_ylabel(f"albedo at {wavelengths[0]:g} nm")
    ax.legend(fontsize=7)
    ctx.figure(fig, "white furnace: directional albedo by two independent estimators")
    details = {"albedo_sampled": {f"{a:g} deg": s.mean for a, _, s in rows},
               "albedo_uniform": {f"{a:g} deg": u.mean for a, u, _ in rows}}
    return Outcome(worst < z, worst, z, "<", f"largest |z| {worst:.2f} (limit {z:.2f})", details)


def _z(diff, se, exact: float = 1e-12) -> float:
    """Largest diff / se; where se is 0 (a deterministic estimator, e.g. a Lambertian's
    constant sample weight) any difference beyond rounding counts as infinitely many sigma."""
    diff, se = np.broadcast_arrays(np.asarray(diff, float), np.asarray(se, float))
    se = np.where(se > exact, se, 0.0)  # rounding-level spreads of a constant are no noise
    with np.errstate(divide="ignore", invalid="ignore"):
        z = np.where(se > 0, diff / se, np.where(diff > exact, np.inf, 0.0))
    return float(np.max(z))


def log_error_histogram(ax, errors, limit, xlabel) -> None:
    """Histogram of log10 errors with the tolerance marked."""
    ax.hist(np.log10(np.maximum(np.ravel(errors), 1e-18)), bins=40)
    ax.axvline(np.log10(limit), color="r", label="tolerance")
    ax.set_xlabel(xlabel)
    ax.legend(fontsize=7)


def register_mitsuba_cases(family, cases, compare_name, reference, tolerance, effort, statistic):
    """One registered check per (name, BSDF, wavelength) case of a reference.mitsuba_* module;
    ``compare_name`` is "module.function" inside bsdflab.reference (imported when run)."""
    import importlib

    from bsdflab.validation.registry import REGISTRY, Check

    module, function = compare_name.rsplit(".", 1)
    for name, bsdf, wavelength in cases:
        def run(ctx, wavelength=wavelength):
            compare = getattr(importlib.import_module(f"bsdflab.reference.{module}"), function)
            return mitsuba_outcome(ctx, compare, wavelength)

        REGISTRY.add(Check(name=f"{family}/mitsuba/{name}", family=family, title=f"{name} against Mitsuba 3",
                           model=repr(bsdf), reference=reference, statistic=statistic, tolerance=tolerance,
                           run=run, effort=effort, make_model=lambda bsdf=bsdf: bsdf, requires=("mitsuba",)))


def reciprocity_outcome(ctx: Context, limit: float) -> Outcome:
    from bsdflab.testing import random_unit_vectors, reciprocity_error

    n = int(ctx.effort["pairs"])
    wi = random_unit_vectors(n, seed=ctx.seed, hemisphere="upper")
    wo = random_unit_vectors(n, seed=ctx.seed + 1, hemisphere="upper")
    err = reciprocity_error(ctx.model, wi, wo, wavelengths=[450.0, 550.0, 650.0])
    fig, ax = new_figure(6.0, 2.8)
    log_error_histogram(ax, err, limit, "log10 relative asymmetry |f(wi,wo) - f(wo,wi)| / max")
    ctx.figure(fig, "reciprocity: relative asymmetry over random pairs")
    worst = float(err.max())
    return Outcome(worst <= limit, worst, limit, "<=", f"max asymmetry {worst:.2e} over {n} pairs")


def z_agreement(value, err, ref, model_error=None):
    """z = (value - ref) / sqrt(err^2 + model_error^2) over (pairs, channels): returns
    (max |z|, its Sidak limit, per-channel sum z^2 and its chi^2 interval over the pairs)."""
    total = err if model_error is None else np.hypot(err, model_error)
    with np.errstate(divide="ignore", invalid="ignore"):
        z = (np.asarray(value) - np.asarray(ref)) / total
    z = np.where(total > 0, z, np.where(np.asarray(value) == np.asarray(ref), 0.0, np.inf))
    z = z.reshape(len(z), -1)
    n_pairs, channels = z.shape
    lo, hi = stats.chi2.ppf([SIGNIFICANCE / channels / 2, 1 - SIGNIFICANCE / channels / 2], n_pairs)
    return z, z_limit(z.size), (z**2).sum(axis=0), (lo, hi)


def z_outcome(ctx: Context, value, err, ref, *, model_error=None, what="estimate") -> Outcome:
    """Outcome of z_agreement: max |z| below the Sidak limit and sum z^2 inside (or, with a
    model error term, below) the chi^2 interval; figure: value vs reference and the z's."""
    z, limit, chi2, (lo, hi) = z_agreement(value, err, ref, model_error)
    worst = float(np.max(np.abs(z)))
    ok_chi2 = bool(np.all(chi2 < hi) and (model_error is not None or np.all(chi2 > lo)))
    fig, (a, b) = new_figure(9.0, 3.2, cols=2)
    v, r, e = (np.asarray(x).reshape(len(z), -1) for x in (value, ref, err))
    a.errorbar(r.ravel(), v.ravel(), yerr=limit * e.ravel(), fmt=".", ms=3, elinewidth=0.5)
    top = float(max(r.max(), v.max()))
    a.plot([0, top], [0, top], "k--", lw=0.8)
    a.set_xlabel("reference")
    a.set_ylabel(f"{what} (+- {limit:.1f} se)")
    b.hist(z.ravel()[np.isfinite(z.ravel())], bins=30, density=True, label="z")
    x = np.linspace(-4, 4, 200)
    b.plot(x, stats.norm.pdf(x), "k", lw=1, label="N(0, 1)")
    b.axvline(limit, color="r", lw=0.8)
    b.axvline(-limit, color="r", lw=0.8)
    b.set_xlabel("z = (estimate - reference) / se")
    b.legend(fontsize=7)
    ctx.figure(fig, f"{what} against the reference (left) and the distribution of z (right)")
    return Outcome(worst < limit and ok_chi2, worst, limit, "<",
                   f"max |z| {worst:.2f} (limit {limit:.2f}); sum z^2 per channel "
                   f"{np.round(chi2, 1).tolist()} in ({lo:.1f}, {hi:.1f}) over {len(z)} pairs",
                   {"sum_z2": chi2, "chi2_interval": [lo, hi], "pairs": len(z)})


def mitsuba_outcome(ctx: Context, compare, wavelength) -> Outcome:
    """A reference.mitsuba_bsdf / mitsuba_rough Comparison as an Outcome: the value is the
    largest error in units of its allowance (the target on well-conditioned pairs, the
    float32 bound on the others), so <= 1 passes when lobes and validity agree too."""
    c = compare(ctx.model, n_pairs=int(ctx.effort["pairs"]), seed=ctx.seed, wavelength=wavelength)
    worst = max([max(c.max_error.values()) / c.target] + [g.max_error_over_bound for g in c.ill_conditioned])
    details = {"max_error": c.max_error, "target": c.target, "n_pairs": c.n_pairs,
               "n_well_conditioned": c.n_well_conditioned, "n_lobe_mismatch": c.n_lobe_mismatch,
               "n_validity_mismatch": c.n_validity_mismatch,
               "ill_conditioned": {g.reason: {"count": g.count, "error_over_bound": g.max_error_over_bound}
                                   for g in c.ill_conditioned}, "reference": c.reference, "report": c.report()}
    mismatches = f"; lobe mismatches {c.n_lobe_mismatch}, validity mismatches {c.n_validity_mismatch}"
    return Outcome(c.passed, worst, 1.0, "<=", c.report().splitlines()[2].strip() + mismatches, details)
