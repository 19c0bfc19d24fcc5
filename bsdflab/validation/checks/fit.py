"""The fit (bsdflab.fit): recovery of known parameters from synthetic data. Datasets are
simulated with truths drawn from the prior (bsdflab.fit.simulate, the thin-film forward
model), fitted by MAP + emcee, and the truths' posterior z-scores are held to the normal
(simulation-based calibration, Talts et al. 2018, in its sum-z^2 form). The model under
test is ``{"fit": callable(data, config) -> draws}``: an over-confident fit must fail."""

from __future__ import annotations

import numpy as np
from scipy import stats

from bsdflab.validation.checks._common import SIGNIFICANCE, z_limit
from bsdflab.validation.figures import new_figure
from bsdflab.validation.registry import REGISTRY, Outcome, effort

PRIOR = {"film_thickness_nm": (430.0, 10.0), "film_ior": (1.83, 0.02)}
TRUTH_TOML = """
[truth]
film_thickness_nm = {d}
film_ior = {A}
pigment_absorption = 0.4
base_albedo = 0.3
[noise]
relative = 0.02
absolute = 0.0002
seed = {seed}
[[measurement]]
geometry = "specular"
angles_deg = [15, 55]
wavelengths_nm = {{ start = 400, stop = 740, step = 40 }}
"""
FIT_TOML = """
[parameters]
film_thickness_nm = {{ prior = "normal", mean = 430.0, sd = 10.0 }}
film_ior = {{ prior = "normal", mean = 1.83, sd = 0.02 }}
pigment_absorption = 0.4
base_albedo = 0.3
[model]
thickness_nodes = 1
[sampler]
walkers = 8
max_steps = {steps}
check_every = 100
seed = {seed}
map_starts = 2
"""
TOLERANCE = (
    f"z = (truth - posterior mean) / posterior sd per dataset and parameter: max |z| below "
    f"the two-sided normal quantile and sum z^2 inside the two-sided chi^2 interval (datasets x 2 "
    f"degrees of freedom; E z^2 = 1 for a calibrated posterior of any shape), the two tests "
    f"Sidak-corrected together at {SIGNIFICANCE}. The posterior's own Monte Carlo error (>= ~100 "
    "effective draws) moves sd by a few per cent, far inside the interval"
)


def _emcee_fit():
    from bsdflab.fit import LogPosterior, run_sampler

    def fit(data, config):
        return run_sampler(LogPosterior(data, config), config.sampler, progress=False).draws()

    return {"fit": fit}


@REGISTRY.check(
    name="fit/recovery/thin-film",
    family="fit",
    title="The fit recovers known film parameters from synthetic data (calibrated posteriors)",
    model="bsdflab.fit: LogPosterior + run_sampler (MAP, emcee 8 walkers) on film thickness and index",
    reference="the truths the data were simulated from (bsdflab.fit.simulate, 2 % noise), drawn "
    "from the prior N(430 nm, 10), N(1.83, 0.02)",
    statistic="sum z^2 over datasets x 2 parameters (max |z| in the message)",
    tolerance=TOLERANCE,
    effort=effort({"datasets": 4, "steps": 400}, {"datasets": 12, "steps": 600}, {"datasets": 48, "steps": 600}),
    make_model=_emcee_fit,
    seed=71,
)
def _recovery(ctx):
    import tomllib

    from bsdflab.fit import FitConfig, SimulationConfig, simulate

    rng = np.random.default_rng(ctx.seed)
    n = int(ctx.effort["datasets"])
    truths, means, sds = [], [], []
    for i in range(n):
        truth = [rng.normal(*PRIOR["film_thickness_nm"]), rng.normal(*PRIOR["film_ior"])]
        sim = SimulationConfig.parse(tomllib.loads(TRUTH_TOML.format(d=truth[0], A=truth[1], seed=ctx.seed + i)))
        config = FitConfig.parse(tomllib.loads(FIT_TOML.format(steps=int(ctx.effort["steps"]), seed=ctx.seed + i)))
        draws = ctx.model["fit"](simulate(sim)[0], config)
        truths.append(truth)
        means.append(draws.mean(axis=0))
        sds.append(draws.std(axis=0, ddof=1))
    truths, means, sds = np.array(truths), np.array(means), np.array(sds)
    z = (truths - means) / sds
    per_test = 1.0 - (1.0 - SIGNIFICANCE) ** 0.5
    limit = z_limit(z.size, per_test)
    lo, hi = stats.chi2.ppf([per_test / 2, 1 - per_test / 2], z.size)
    z2, worst = float(np.sum(z**2)), float(np.max(np.abs(z)))
    fig, ax = new_figure(5.0, 3.0)
    ax.scatter(z[:, 0], z[:, 1], s=12)
    ax.axvline(0, color="k", lw=0.5)
    ax.axhline(0, color="k", lw=0.5)
    ax.set_xlabel("z of film thickness")
    ax.set_ylabel("z of film index")
    ctx.figure(fig, "truth - posterior mean in posterior sd, per dataset")
    ok = worst < limit and lo <= z2 <= hi
    return Outcome(
        ok,
        z2,
        hi,
        "in",
        f"sum z^2 {z2:.2f} in ({lo:.2f}, {hi:.2f}) over {n} datasets x 2; "
        f"max |z| {worst:.2f} (limit {limit:.2f}); median posterior sd {np.median(sds[:, 0]):.2f} nm, "
        f"{np.median(sds[:, 1]):.4f} (prior 10 nm, 0.02)",
        {
            "z": z,
            "chi2_interval": [lo, hi],
            "max_abs_z_limit": limit,
            "posterior_sd": {"film_thickness_nm": sds[:, 0], "film_ior": sds[:, 1]},
        },
    )
