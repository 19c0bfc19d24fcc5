"""Layered PFMC: the quadrature oracle (tmm + Gauss-Legendre), Mitsuba's plastic,
O(N^-1/2) convergence, reciprocity and energy of a lossless stack."""
from __future__ import annotations

import numpy as np

from bsdflab import Dielectric, Diffuse, Layered, Slab
from bsdflab.testing import random_unit_vectors, spherical_directions
from bsdflab.validation.checks._common import SIGNIFICANCE, furnace_outcome, z_outcome
from bsdflab.validation.figures import new_figure
from bsdflab.validation.registry import REGISTRY, Outcome, effort

Z_TOLERANCE = ("z = (PFMC - reference) / se per pair and channel; max |z| below the two-sided "
               f"normal quantile Sidak-corrected at {SIGNIFICANCE} over all z, and per channel "
               "sum z^2 inside its chi^2 interval over the independent pairs (so errors that "
               "are overstated fail too)")
FILMS = {"bare": None, "guanine-400nm": [{"material": 1.83, "thickness_nm": 400.0}]}
WAVELENGTHS = [450.0, 550.0, 650.0]


def _coated(film, sigma_a, samples):
    return Layered([Dielectric(1.55, 1.0, film=FILMS[film])], [Slab(2.0, sigma_a=sigma_a)], Diffuse(0.7),
                   samples=samples)


for _film in FILMS:
    @REGISTRY.check(name=f"layered/oracle/{_film}", family="layered",
                    title=f"PFMC against the coated-diffuse oracle ({_film} top)",
                    model=f"Layered(Dielectric(1.55, film={_film}), Slab(2 um, sigma_a 0.15), Diffuse(0.7))",
                    reference="bsdflab.oracles.CoatedDiffuseOracle (tmm powers, adaptive quadrature)",
                    statistic="max |z| over pairs x 3 wavelengths", tolerance=Z_TOLERANCE,
                    effort=effort({"pairs": 16, "samples": 2000}, {"pairs": 64, "samples": 8000},
                                  {"pairs": 256, "samples": 20000}),
                    make_model=lambda _film=_film: _coated(_film, 0.15, 256), seed=31, requires=("tmm",))
    def _oracle(ctx, _film=_film):
        from bsdflab.oracles import CoatedDiffuseOracle

        n = int(ctx.effort["pairs"])
        wi = random_unit_vectors(n, seed=ctx.seed, hemisphere="upper")
        wo = random_unit_vectors(n, seed=ctx.seed + 1, hemisphere="upper")
        value, err = ctx.model.eval_with_error(wi, wo, wavelengths=WAVELENGTHS,
                                               samples=int(ctx.effort["samples"]), seed=ctx.seed + 2)
        ref = CoatedDiffuseOracle(int_ior=1.55, ext_ior=1.0, film=FILMS[_film], thickness_um=2.0,
                                  sigma_a=0.15, base_reflectance=0.7).eval(wi, wo, wavelengths=WAVELENGTHS)
        return z_outcome(ctx, value, err, ref, what="PFMC eval")


@REGISTRY.check(name="layered/mitsuba/plastic", family="layered",
                title="PFMC coat-over-diffuse against Mitsuba's plastic (nonlinear)",
                model="Layered(Dielectric(1.5), Slab(0), Diffuse(0.8))",
                reference="Mitsuba 3 plastic, nonlinear=true (the same model in closed form)",
                statistic="max |z| over pairs", tolerance=Z_TOLERANCE + "; Mitsuba's fitted internal "
                "diffuse Fresnel reflectance (~1e-3) and float32 enter as a 2e-3 relative model error, "
                "so only the upper chi^2 bound applies",
                effort=effort({"pairs": 16, "samples": 4000}, {"pairs": 64, "samples": 20000}),
                make_model=lambda: Layered([Dielectric(1.5, 1.0)], [Slab(0.0)], Diffuse(0.8), samples=256),
                seed=32, requires=("mitsuba",))
def _plastic(ctx):
    from bsdflab.reference.mitsuba_calls import query

    n = int(ctx.effort["pairs"])
    wi = random_unit_vectors(n, seed=ctx.seed, hemisphere="upper")
    wo = random_unit_vectors(n, seed=ctx.seed + 1, hemisphere="upper")
    value, err = ctx.model.eval_with_error(wi, wo, wavelengths=[550.0], samples=int(ctx.effort["samples"]),
                                           seed=ctx.seed + 2)
    plugin = {"type": "plastic", "int_ior": 1.5, "ext_ior": 1.0, "nonlinear": True,
              "diffuse_reflectance": {"type": "rgb", "value": [0.8, 0.8, 0.8]}}
    ref = query(plugin, wi, wo, np.zeros(n), np.zeros((n, 2))).eval[:, 0]
    return z_outcome(ctx, value[:, 0], err[:, 0], ref, model_error=2e-3 * ref, what="PFMC eval")


@REGISTRY.check(name="layered/convergence", family="layered", title="PFMC error falls as N^-1/2",
                model="bsdflab.presets.xenopeltis()", reference="Monte Carlo theory: spread ~ N^-1/2",
                statistic="|slope + 1/2| of log(spread over seeds) vs log(walks)",
                tolerance="3 standard errors of the slope: the standard error of each log spread is "
                          "bootstrapped over the S seeds (PFMC estimates are heavy-tailed, so the normal "
                          "value 1/sqrt(2(S-1)) would understate it), the slope is the weighted least-"
                          "squares fit with weights 1/se^2, and its standard error "
                          "1/sqrt(sum w (log N - weighted mean)^2)",
                effort=effort({"seeds": 40, "counts": [128, 512, 2048]},
                              {"seeds": 60, "counts": [128, 512, 2048, 8192]}),
                make_model=lambda: __import__("bsdflab").presets.xenopeltis(), seed=33)
def _convergence(ctx):
    counts = np.array(ctx.effort["counts"])
    wi, wo = spherical_directions(np.arccos(0.8), 0.0), spherical_directions(np.arccos(0.6), 2.5)
    spreads, errs, se_log = [], [], []
    boot = np.random.default_rng(ctx.seed)
    for n in counts:
        # the statistic is the spread over seeds; the reported error is only drawn (no error walks)
        runs = [ctx.model.eval_with_error(wi, wo, wavelengths=[550.0], samples=int(n), seed=ctx.seed + s,
                                          error_walks=0)
                for s in range(int(ctx.effort["seeds"]))]
        means = np.array([r[0][0, 0] for r in runs])
        spreads.append(means.std(ddof=1))
        errs.append(np.mean([r[1][0, 0] for r in runs]))
        resampled = means[boot.integers(0, len(means), (400, len(means)))]
        se_log.append(np.log(resampled.std(axis=1, ddof=1)).std(ddof=1))
    x, y, w = np.log(counts), np.log(spreads), 1.0 / np.square(se_log)
    xm = np.sum(w * x) / np.sum(w)
    slope = float(np.sum(w * (x - xm) * (y - np.sum(w * y) / np.sum(w))) / np.sum(w * (x - xm) ** 2))
    limit = 3.0 / np.sqrt(np.sum(w * (x - xm) ** 2))
    fig, ax = new_figure(6.0, 3.2)
    ax.loglog(counts, spreads, "o-", label="spread over seeds")
    ax.loglog(counts, errs, "s", label="reported standard error (mean)")
    ax.loglog(counts, spreads[0] * np.sqrt(counts[0] / counts), "k--", lw=0.8, label="N^-1/2")
    ax.set_xlabel("walks per estimate N")
    ax.set_ylabel("error of eval")
    ax.legend(fontsize=7)
    ctx.figure(fig, f"convergence: slope {slope:.3f} (expected -0.5)")
    return Outcome(abs(slope + 0.5) < limit, abs(slope + 0.5), float(limit), "<", f"slope {slope:.3f}",
                   {"slope": slope, "spreads": spreads, "reported_errors": errs,
                    "bootstrap_se_of_log_spread": se_log})


@REGISTRY.check(name="layered/reciprocity", family="layered", title="PFMC is reciprocal (within its noise)",
                model="bsdflab.presets.xenopeltis()", reference="Helmholtz reciprocity f(wi,wo) = f(wo,wi)",
                statistic="max |z| of f(wi,wo) - f(wo,wi) over pairs", tolerance=Z_TOLERANCE,
                effort=effort({"pairs": 16, "samples": 2000}, {"pairs": 48, "samples": 8000}),
                make_model=lambda: __import__("bsdflab").presets.xenopeltis(), seed=34)
def _reciprocity(ctx):
    n = int(ctx.effort["pairs"])
    wi = random_unit_vectors(n, seed=ctx.seed, hemisphere="upper")
    wo = random_unit_vectors(n, seed=ctx.seed + 1, hemisphere="upper")
    samples = int(ctx.effort["samples"])
    a, ea = ctx.model.eval_with_error(wi, wo, wavelengths=[550.0], samples=samples, seed=ctx.seed + 2)
    b, eb = ctx.model.eval_with_error(wo, wi, wavelengths=[550.0], samples=samples, seed=ctx.seed + 3)
    fa, fb = a[:, 0] / wo[:, 2], b[:, 0] / wi[:, 2]
    sa, sb = ea[:, 0] / wo[:, 2], eb[:, 0] / wi[:, 2]
    return z_outcome(ctx, fa, np.hypot(sa, sb), fb, what="f(wi, wo) against f(wo, wi)")


@REGISTRY.check(name="layered/furnace/lossless", family="layered", title="Lossless coat over white diffuse: albedo 1",
                model="Layered(Dielectric(1.5), Slab(0), Diffuse(1.0)) walks plus its exact delta reflection",
                reference="energy conservation: sampled albedo (delta included) = 1",
                statistic="largest |z| of the mean sample weight against 1 (and sampled vs uniform)",
                tolerance="as the basic white furnace; the uniform estimator misses the delta lobe, so "
                          "it is compared with the sampled one minus the delta reflectance",
                effort=effort({"samples": 100_000}, {"samples": 400_000}),
                make_model=lambda: Layered([Dielectric(1.5, 1.0)], [Slab(0.0)], Diffuse(1.0), samples=1), seed=35)
def _furnace(ctx):
    return furnace_outcome(ctx, (0.0, 60.0, 84.0), 1.0,
                           uniform_offset=lambda wi: ctx.model.delta_reflectance(wi, wavelengths=[550.0]))
