"""Coverage of PFMC's stated errors against adding-doubling (docs/coverage.md): how often a
PFMC table cell (or an ``eval_with_error`` pair) misses adding-doubling by more than k of
its own standard errors, against the normal 2 (1 - Phi(k)). The model under test is the
estimator: ``{"stack": Layered, "tabulate": tabulate}`` for tables, ``{"stack": Layered,
"estimate": f(stack, wi, wo, seed)}`` for pairs; a ``tabulate`` that understates its errors,
or pairs' errors from their own walks alone (error_walks=0), must fail."""

from __future__ import annotations

import numpy as np
from scipy import stats

from bsdflab.testing import random_unit_vectors
from bsdflab.validation.checks._common import SIGNIFICANCE
from bsdflab.validation.figures import new_figure
from bsdflab.validation.registry import REGISTRY, Outcome, effort

WAVELENGTHS = [450.0, 550.0, 650.0]
KS = (2.0, 3.0, 4.0)
PER_K = 1.0 - (1.0 - SIGNIFICANCE) ** (1.0 / len(KS))  # Sidak over the three k
TOLERANCE = (
    "per k = 2, 3, 4 the count of units with |z| > k, z = (PFMC - AD) / hypot(PFMC se, AD "
    "bound), is binomial(units, 2 (1 - Phi(k))) when the errors are honest (one channel per "
    "cell or pair, (seed + unit) mod 3, so units share no walks); each two-sided binomial "
    f"p-value at least the Sidak-corrected {PER_K:.4f} (family {SIGNIFICANCE} over the three k)"
)


def _plastic():
    import bsdflab as bl

    return bl.Layered([bl.Dielectric(1.5)], [bl.Slab(1.0, sigma_a=0.2, sigma_s=1.0)], bl.Diffuse(0.6))


def _table_estimator():
    from bsdflab.tables import tabulate

    return {"stack": _plastic(), "tabulate": tabulate}


def count_rows(z: np.ndarray) -> list[dict]:
    """Per k: observed share, expected share, count, units and the binomial p-value."""
    z = z[np.isfinite(z)]
    rows = []
    for k in KS:
        p0 = 2.0 * stats.norm.sf(k)
        c = int(np.count_nonzero(np.abs(z) > k))
        rows.append(
            {
                "k": k,
                "observed": c / z.size,
                "expected": p0,
                "count": c,
                "units": int(z.size),
                "p_value": float(stats.binomtest(c, z.size, p0).pvalue),
            }
        )
    return rows


def _one_channel(z: np.ndarray, seed: int) -> np.ndarray:
    z = z.reshape(-1, z.shape[-1])
    return z[np.arange(len(z)), (seed + np.arange(len(z))) % z.shape[-1]]


def _outcome(ctx, z: np.ndarray, what: str) -> tuple[bool, float, str, dict]:
    rows = count_rows(z)
    worst = min(r["p_value"] for r in rows)
    fig, ax = new_figure(5.5, 3.0)
    ax.hist(np.clip(z, -6, 6), bins=40, density=True, label=f"z ({len(z)} units)")
    x = np.linspace(-6, 6, 300)
    ax.plot(x, stats.norm.pdf(x), "k", lw=1, label="N(0, 1)")
    ax.set_xlabel("z = (PFMC - adding-doubling) / stated error")
    ax.legend(fontsize=7)
    ctx.figure(fig, f"{what}: distribution of z against the normal")
    message = "; ".join(
        f"k={r['k']:g}: {r['count']}/{r['units']} = {r['observed']:.4f} "
        f"(normal {r['expected']:.4f}, p {r['p_value']:.2g})"
        for r in rows
    )
    return worst >= PER_K, worst, message, {"per_k": rows, "mean_z": float(np.mean(z)), "sd_z": float(np.std(z))}


@REGISTRY.check(
    name="coverage/table-cells/plastic",
    family="coverage",
    title="PFMC table cell errors cover adding-doubling at the normal rate",
    model="tabulate(Layered(Dielectric(1.5), Slab(1, sigma_a 0.2, sigma_s 1), Diffuse(0.6)), "
    "3 x 4 x 3 grid, the user's pilot and rel_error 0.05)",
    reference="the adding-doubling table of the same grid (tabulate method='adding-doubling', rel_error 0.002)",
    statistic="smallest binomial p-value over k = 2, 3, 4",
    tolerance=TOLERANCE,
    effort=effort({"seeds": 10}, {"seeds": 40}, {"seeds": 200}),
    make_model=_table_estimator,
    seed=61,
)
def _table_cells(ctx):
    from bsdflab.tables import TableGrid, tabulate

    stack, tab = ctx.model["stack"], ctx.model["tabulate"]
    grid = TableGrid(3, 4, 3)
    ad = tabulate(stack, grid, rel_error=0.002, wavelengths=WAVELENGTHS, method="adding-doubling", progress=False)
    zs = []
    for seed in range(ctx.seed, ctx.seed + int(ctx.effort["seeds"])):
        mc = tab(stack, grid, rel_error=0.05, wavelengths=WAVELENGTHS, progress=False, seed=seed)
        zs.append(_one_channel((mc.values - ad.values) / np.hypot(mc.stderr, ad.stderr), seed))
    ok, worst, message, details = _outcome(ctx, np.concatenate(zs), "table cells")
    return Outcome(ok, worst, PER_K, ">=", message, details)


def _estimate(stack, wi, wo, seed):
    """The estimator under test: ``Layered.estimate`` at the stack's default 256 walks and its
    default ``error_walks`` (a mutation passes error_walks=0: the value's own spread)."""
    return stack.estimate(wi, wo, WAVELENGTHS, samples=256, seed=seed, scattered_only=True)


def _pair_estimator(make_stack):
    return lambda: {"stack": make_stack(), "estimate": _estimate}


def _snake():
    from bsdflab.presets import preset

    return preset("xenopeltis")


PAIR_EFFORT = effort({"pairs": 24, "seeds": 4}, {"pairs": 24, "seeds": 40}, {"pairs": 24, "seeds": 200})
PAIR_MODEL = "Layered.estimate(scattered_only=True) of the {} at its default 256 walks and error_walks (4 x 256)"
PAIR_REFERENCE = "bsdflab.solvers.solve(...).eval_with_error(scattered_only=True)"


def _pairs(ctx):
    from bsdflab.solvers import solve

    stack, estimate = ctx.model["stack"], ctx.model["estimate"]
    n = int(ctx.effort["pairs"])
    wi = random_unit_vectors(n, seed=ctx.seed, hemisphere="upper")
    wo = random_unit_vectors(n, seed=ctx.seed + 1, hemisphere="upper")
    ref, bound = solve(stack, WAVELENGTHS).eval_with_error(wi, wo, scattered_only=True)
    zs = []
    for seed in range(ctx.seed, ctx.seed + int(ctx.effort["seeds"])):
        e = estimate(stack, wi, wo, seed)
        zs.append(_one_channel((e.value - ref) / np.hypot(e.stderr, bound), seed))
    ok, worst, message, details = _outcome(ctx, np.concatenate(zs), "eval_with_error pairs")
    return Outcome(ok, worst, PER_K, ">=", message, details)


for _name, _make, _seed in (("plastic", _plastic, 62), ("xenopeltis", _snake, 63)):
    REGISTRY.check(
        name=f"coverage/eval-with-error-pairs/{_name}",
        family="coverage",
        title=f"eval_with_error's per-pair errors cover adding-doubling at the normal rate ({_name})",
        model=PAIR_MODEL.format(f"{_name} stack"),
        reference=PAIR_REFERENCE,
        statistic="smallest binomial p-value over k = 2, 3, 4",
        tolerance=TOLERANCE,
        effort=PAIR_EFFORT,
        make_model=_pair_estimator(_make),
        seed=_seed,
    )(_pairs)
