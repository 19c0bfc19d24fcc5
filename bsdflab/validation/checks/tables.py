"""Tables: a tabulated layered BSDF against independent PFMC estimates at its nodes (error
map and scatter), a Diffuse table exact to float32, and the table's sampler (chi-square)."""
from __future__ import annotations

import numpy as np

from bsdflab.testing import random_unit_vectors, spherical_directions
from bsdflab.validation.checks._common import CHI2_TOLERANCE, chi2_outcome, z_outcome
from bsdflab.validation.checks.layered import Z_TOLERANCE
from bsdflab.validation.figures import new_figure
from bsdflab.validation.registry import REGISTRY, Outcome, effort

WAVELENGTHS = [450.0, 550.0, 650.0]
GRIDS = effort({"grid": [4, 6, 5], "check_samples": 4000}, {"grid": [6, 10, 9], "check_samples": 8000},
               {"grid": [12, 24, 13], "check_samples": 16000})


# the snake's table is tabulated once per grid in a run, with this seed, and read by both
# checks below (the chi-square check's own seed draws its samples): 1.5 CPU-s at quick
TABLE_SEED = 41
_TABLES: dict[tuple[int, ...], tuple] = {}


def _xenopeltis_table(ctx):
    """(model, TableBSDF, table) for the snake preset, tabulated at 3 wavelengths with
    4096 walks per cell at least (fewer leave PFMC's heavy tail under-sampled and the cell
    errors underestimated; see tests/test_tables.py's xeno fixture)."""
    import bsdflab as bl
    from bsdflab.tables import TableBSDF, TableGrid, tabulate

    grid = tuple(int(n) for n in ctx.effort["grid"])
    if grid not in _TABLES:
        model = bl.presets.xenopeltis(samples=64)
        table = tabulate(model, TableGrid(*grid), rel_error=0.03, wavelengths=WAVELENGTHS,
                         min_samples=4096, seed=TABLE_SEED, progress=False)
        _TABLES[grid] = (model, TableBSDF(table), table)
    return _TABLES[grid]


@REGISTRY.check(name="tables/xenopeltis-vs-pfmc", family="tables",
                title="The snake's table against fresh PFMC estimates at its nodes",
                model="TableBSDF of bsdflab.presets.xenopeltis (3 wavelengths)",
                reference="direct PFMC eval_with_error with another seed",
                statistic="max |z| over nodes x channels, z = (T - P) / sqrt(se_T^2 + se_P^2)",
                tolerance=Z_TOLERANCE + "; at the nodes the lookup does not interpolate, so no "
                          "interpolation bound enters (off-node accuracy: tests/test_tables.py)",
                effort=GRIDS, seed=41)
def _table_vs_pfmc(ctx):
    model, tb, table = _xenopeltis_table(ctx)
    g = table.grid
    ti, to, ph = np.meshgrid(g.theta_i, g.theta_o, g.phi, indexing="ij")
    wi = spherical_directions(ti.ravel(), 0.0)
    wo = spherical_directions(to.ravel(), ph.ravel())
    cos_o = wo[:, 2:3]
    looked_up = tb.eval(wi, wo)
    sigma_t = table.stderr[0, 0].reshape(-1, 3).astype(float) * cos_o
    ref, ref_err = model.eval_with_error(wi, wo, wavelengths=WAVELENGTHS,
                                         samples=int(ctx.effort["check_samples"]), seed=ctx.seed + 1)
    out = z_outcome(ctx, looked_up, np.hypot(sigma_t, ref_err), ref, what="table")
    z = np.abs((looked_up - ref) / np.hypot(sigma_t, ref_err)).max(axis=1).reshape(ti.shape).max(axis=2)
    fig, ax = new_figure(5.5, 3.6)
    im = ax.imshow(z.T, origin="lower", aspect="auto", cmap="viridis", vmin=0, vmax=max(out.limit, z.max()),
                   extent=(0, 90, 0, 90))
    fig.colorbar(im, ax=ax, label="max |z| over phi and channels")
    ax.set_xlabel("theta_i (deg)")
    ax.set_ylabel("theta_o (deg)")
    ax.set_title(f"error map (limit {out.limit:.2f})", fontsize=9)
    ctx.figure(fig, "table error map at the nodes: |table - PFMC| in standard errors")
    return out


@REGISTRY.check(name="tables/diffuse-exact", family="tables", title="A Diffuse table is exact to float32",
                model="TableBSDF of Diffuse(0.6)", reference="closed form f = rho / pi",
                statistic="max |T - A| / A over random directions (both hemispheres for wo)",
                tolerance="2^-23: f is constant, so interpolation and the clamped extrapolation are "
                          "exact and only float32 storage (2^-24) plus double arithmetic remains",
                effort=effort({"pairs": 2000}, {"pairs": 20000}), seed=42)
def _diffuse_table(ctx):
    from bsdflab import Diffuse
    from bsdflab.tables import TableBSDF, TableGrid, tabulate

    model = Diffuse(0.6)
    tb = TableBSDF(tabulate(model, TableGrid(3, 4, 2), progress=False))
    n = int(ctx.effort["pairs"])
    wi = random_unit_vectors(n, seed=ctx.seed, hemisphere="upper")
    wo = random_unit_vectors(n, seed=ctx.seed + 1)
    t, a = tb.eval(wi, wo), model.eval(wi, wo)
    up = wo[:, 2] > 0
    rel = float(np.max(np.abs(t[up] - a[up]) / a[up]))
    below = float(np.max(np.abs(t[~up])))
    limit = 2.0 ** -23
    return Outcome(rel <= limit and below == 0.0, rel, limit, "<=",
                   f"max relative error {rel:.2e}; max value below the surface {below:g}")


@REGISTRY.check(name="tables/chi2/xenopeltis", family="tables", title="The table's sampler follows its pdf",
                model="TableBSDF of bsdflab.presets.xenopeltis", reference="the table's own pdf",
                statistic="smallest p-value over theta_i = 0, 40, 85 deg",
                tolerance=CHI2_TOLERANCE + "; quadrature order 10 for the exact top lobe (GGX 0.08)",
                effort=effort({"grid": [4, 6, 5], "samples": 100_000}, {"grid": [6, 10, 9], "samples": 400_000}),
                seed=43)
def _table_chi2(ctx):
    _, tb, _ = _xenopeltis_table(ctx)
    ctx.model = tb
    return chi2_outcome(ctx, (0.0, 40.0, 85.0), quadrature_order=10)

