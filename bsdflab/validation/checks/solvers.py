"""The adding-doubling solver (bsdflab.solvers) against PFMC (a z-test, the solver's
a-posteriori bound added to the allowance) and against the independent numpy oracle
(bsdflab.oracles.AddingDoublingOracle, deterministic). The model under test is the pair
{"stack": Layered, "solve": solve}: a broken ``solve`` must fail both checks."""

from __future__ import annotations

import numpy as np

from bsdflab.testing import random_unit_vectors, spherical_directions
from bsdflab.validation.checks._common import SIGNIFICANCE, z_limit
from bsdflab.validation.figures import new_figure
from bsdflab.validation.registry import REGISTRY, Outcome, effort

WAVELENGTHS = [450.0, 550.0, 650.0]
RTOL_ORACLE = 2e-5  # the solver's default truncations against the oracle's ~1e-7 (docs/solvers.md)


def _pairs(n: int, seed: int):
    """n random pairs over the upper hemisphere, the first ones grazing (85-88 deg)."""
    wi = random_unit_vectors(n, seed=seed, hemisphere="upper")
    wo = random_unit_vectors(n, seed=seed + 1, hemisphere="upper")
    graze = spherical_directions(np.radians([85.0, 88.0]), [0.0, 1.0])
    wi[:2], wo[2:4] = graze, graze
    return wi, wo


def _snake():
    from bsdflab.presets import preset
    from bsdflab.solvers import solve

    return {"stack": preset("xenopeltis"), "solve": solve}


def _smooth_coat():
    import bsdflab as bl
    from bsdflab.solvers import solve

    slab = bl.Slab(1.0, sigma_a=0.3, sigma_s=0.7, phase={"type": "hg", "g": 0.6})
    return {"stack": bl.Layered([bl.Dielectric(1.5, 1.0)], [slab], bl.Diffuse(0.5)), "solve": solve}


@REGISTRY.check(
    name="solvers/adding-doubling-vs-pfmc/xenopeltis",
    family="solvers",
    title="Adding-doubling against PFMC on the snake (scattered part, grazing pairs)",
    model="bsdflab.solvers.solve(presets.xenopeltis) (adding-doubling, default settings)",
    reference="PFMC Layered.estimate(scattered_only=True) with independent walks per pair",
    statistic="max over pairs x 3 wavelengths of z = (|PFMC - AD| - AD bound) / PFMC se",
    tolerance=f"two-sided normal quantile Sidak-corrected at {SIGNIFICANCE} over pairs x "
    "channels (the channels of a pair share walks: positively dependent, for which "
    "Sidak stays conservative); the solver's deterministic bound widens the allowance",
    effort=effort({"pairs": 8, "samples": 10000}, {"pairs": 24, "samples": 20000}, {"pairs": 64, "samples": 40000}),
    make_model=_snake,
    seed=51,
)
def _vs_pfmc(ctx):
    stack, solve = ctx.model["stack"], ctx.model["solve"]
    wi, wo = _pairs(int(ctx.effort["pairs"]), ctx.seed)
    ref, bound = solve(stack, WAVELENGTHS).eval_with_error(wi, wo, scattered_only=True)
    est = stack.estimate(
        wi, wo, wavelengths=WAVELENGTHS, samples=int(ctx.effort["samples"]), seed=ctx.seed + 2, scattered_only=True
    )
    z = (np.abs(est.value - ref) - bound) / est.stderr
    limit = z_limit(z.size)
    worst = float(np.max(z))
    fig, ax = new_figure(5.0, 3.2)
    ax.errorbar(ref.ravel(), est.value.ravel(), yerr=limit * est.stderr.ravel(), fmt=".", ms=3, elinewidth=0.5)
    top = float(max(ref.max(), est.value.max()))
    ax.plot([0, top], [0, top], "k--", lw=0.8)
    ax.set_xlabel("adding-doubling f (scattered part)")
    ax.set_ylabel(f"PFMC (+- {limit:.1f} se)")
    ctx.figure(fig, "PFMC against adding-doubling per pair and wavelength")
    return Outcome(
        worst <= limit,
        worst,
        limit,
        "<=",
        f"max z {worst:.2f} (limit {limit:.2f}) over {z.shape[0]} pairs x {z.shape[1]} channels; "
        f"median PFMC relative se {np.median(est.stderr / ref):.3f}, max AD bound "
        f"{np.max(bound / ref):.1e}",
        {"median_rel_se": float(np.median(est.stderr / ref)), "max_rel_bound": float(np.max(bound / ref))},
    )


@REGISTRY.check(
    name="solvers/adding-doubling-vs-oracle/smooth-coat",
    family="solvers",
    title="Adding-doubling against the independent numpy oracle (smooth coat, HG slab)",
    model="bsdflab.solvers.solve(Layered(Dielectric(1.5), Slab(tau 1, albedo 0.7, HG 0.6), Diffuse(0.5)))",
    reference="bsdflab.oracles.AddingDoublingOracle (numpy, written independently; ~1e-7)",
    statistic="max relative difference over pairs x 3 wavelengths (grazing pairs included)",
    tolerance=f"{RTOL_ORACLE:g}: deterministic; the solver's default truncations (nodes per "
    "panel, start depth, orders) measured in docs/solvers.md, the oracle's 1e-7 "
    "in docs/oracles.md",
    effort=effort({"pairs": 16}, {"pairs": 64}),
    make_model=_smooth_coat,
    seed=52,
)
def _vs_oracle(ctx):
    from bsdflab.oracles import AddingDoublingOracle

    stack, solve = ctx.model["stack"], ctx.model["solve"]
    wi, wo = _pairs(int(ctx.effort["pairs"]), ctx.seed)
    ours = solve(stack, WAVELENGTHS).eval(wi, wo)
    ref = AddingDoublingOracle.from_layered(stack).eval(wi, wo, wavelengths=WAVELENGTHS)
    rel = float(np.max(np.abs(ours - ref) / ref))
    return Outcome(
        rel <= RTOL_ORACLE,
        rel,
        RTOL_ORACLE,
        "<=",
        f"max relative difference {rel:.2e} over {len(wi)} pairs x {len(WAVELENGTHS)} wavelengths",
    )
