"""Tables by adding-doubling (tabulate(..., method="adding-doubling")): the same format as
PFMC tables, method and settings in the header, values equal to the solver's at the cell
directions, and statistically consistent with a PFMC table of the same model (z-test
per cell, Sidak-corrected over the cells, family alpha 0.01)."""
from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from bsdflab import from_dict
from bsdflab.presets import preset
from bsdflab.tables import TableGrid, tabulate
from bsdflab.testing import sidak_significance

WL = [450.0, 550.0, 650.0]
GRID = TableGrid(3, 4, 3, thickness_nm=(350.0, 450.0))


def test_01_format_header_and_agreement_with_pfmc_table():
    model = preset("xenopeltis")
    ad = tabulate(model, GRID, rel_error=0.05, wavelengths=WL, method="adding-doubling", progress=False)
    assert ad.meta["method"] == "adding-doubling"
    assert ad.meta["solver"]["nodes"] == 16 and ad.split_direct and ad.lobes == ("reflection",)
    assert ad.meta["error_bound_max_rel"] < 0.01
    # 32768 walks per cell, not the tabulator's 512: a snake walk's contribution is
    # right-skewed (rare long paths carry much), so a 512-walk mean usually falls below the
    # true value with a standard error that reads low, and the per-cell z of the normal
    # approximation had heavy negative tails (max |z| 4.5-5.8 at 5 of 12 seeds, every one
    # a PFMC deficit). At 32768 walks 16 of 16 seed-estimator runs passed (max |z| 3.7), and
    # at 65536 the cells' z had mean 0.06, sd 0.95 against a tight adding-doubling table.
    mc = tabulate(model, GRID, rel_error=0.05, wavelengths=WL, progress=False, seed=3, min_samples=32768)
    assert ad.values.shape == mc.values.shape
    z_max = stats.norm.isf(sidak_significance(0.01, ad.values.size) / 2)
    z = np.abs(ad.values - mc.values) / np.hypot(mc.stderr, ad.stderr)
    print(f"max z {z.max():.2f} (limit {z_max:.2f}) over {z.size} cell-channels")
    assert z.max() <= z_max
    # Power: 10 % less melanin in the solved model (the PFMC table unchanged) is rejected.
    other = tabulate(preset("xenopeltis", pigment_absorption=1.08), GRID, rel_error=0.05, wavelengths=WL,
                     method="adding-doubling", progress=False)
    assert (np.abs(other.values - mc.values) / np.hypot(mc.stderr, other.stderr)).max() > z_max


@pytest.fixture(scope="module")
def snake_ad_table():
    return tabulate(preset("xenopeltis"), GRID, rel_error=0.05, wavelengths=WL, method="adding-doubling",
                    progress=False)


@pytest.mark.slow
@pytest.mark.parametrize("estimator", ["pfmc2", "pfmc"])
@pytest.mark.parametrize("seed", range(20))
def test_01b_agreement_at_20_consecutive_seeds(snake_ad_table, seed, estimator):
    """test_01's z-test at seeds 0-19 for both estimators (issue 32: its fixed seed passed
    while 25-40 % of other seeds exceeded the Sidak limit with version 6's cell errors;
    version 7 pools the pilot's walk spread into them, docs/coverage.md). Each seed is its
    own family at alpha 0.01 (40 such runs with exact errors would all pass with
    probability 0.99^40 = 0.67); the seeds are fixed: 20 of 20 recorded passing for each estimator."""
    ad = snake_ad_table
    model = from_dict({**preset("xenopeltis").to_dict(), "estimator": estimator})
    mc = tabulate(model, GRID, rel_error=0.05, wavelengths=WL, progress=False, seed=seed, min_samples=32768)
    z_max = stats.norm.isf(sidak_significance(0.01, ad.values.size) / 2)
    z = np.abs(ad.values - mc.values) / np.hypot(mc.stderr, ad.stderr)
    assert z.max() <= z_max, f"seed {seed}: max z {z.max():.2f} > {z_max:.2f}"


def test_02_bad_method():
    with pytest.raises(ValueError, match="method must be one of"):
        tabulate(preset("xenopeltis"), GRID, method="exact", progress=False)
    with pytest.raises(ValueError, match="tabulates Layered models"):
        tabulate(preset("xenopeltis-diffuse"), GRID, method="adding-doubling", progress=False)


def test_03_shared_solve_across_thicknesses_is_exact():
    """Solution.with_model (what lies below a rough top solved once) gives the values of
    a fresh solve of the other thickness, to round-off."""
    from bsdflab.solvers import solve
    from bsdflab.tables.deterministic import with_film_thickness
    from bsdflab.testing import random_unit_vectors

    wi = random_unit_vectors(6, seed=1, hemisphere="upper")
    wo = random_unit_vectors(6, seed=2, hemisphere="upper")
    model = preset("xenopeltis")
    other = with_film_thickness(model, 450.0)
    shared = solve(model, WL).with_model(other).eval_with_error(wi, wo)
    fresh = solve(other, WL).eval_with_error(wi, wo)
    for a, b in zip(shared, fresh):
        assert np.allclose(a, b, rtol=1e-12, atol=0)
