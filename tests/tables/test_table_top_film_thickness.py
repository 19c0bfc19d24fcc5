"""Tables with a film-thickness axis give the node's thickness to the top film alone
(estimator version 8): a table of a stack with a filmed top and a filmed base, read at
the node T, against the same stack made with its top film at T explicitly (thickness
None), which nobody asks to change its base.

- PFMC table cells vs the explicit model's scattered part (``Layered.estimate``,
  independent seed): z-tests from both stated standard errors, Sidak over the cells and
  channels at a family-wise alpha of 1e-3;
- adding-doubling table cells vs the explicit model's own solve (default, tighter
  settings, no film lookup): |difference| within the two solves' error bounds plus
  float32 storage;
- the lookup's delta lobes at T (both methods) vs the explicit model's delta stack: the
  same 1-D adding from an independently built stack, to 1e-9.
Mutations run once: the walk and its film lookup giving every boundary the node's film
(the semantics before version 8) fails the PFMC cells (z 6.1 against a bound of 4.6); the
delta stack doing so fails every delta-lobe test (at T and at the default); adding-doubling's
``with_film_thickness`` scaling the base's film too fails its cells."""

from __future__ import annotations

from statistics import NormalDist

import numpy as np
import pytest

import bsdflab as bl
from bsdflab.lobes import Lobe
from bsdflab.solvers import solve
from bsdflab.tables import TableBSDF, TableGrid, tabulate
from bsdflab.tables.delta import delta_stack
from bsdflab.tables.deterministic import lobe_directions

WL = [450.0, 550.0, 650.0]
OWN_NM, T_NM = 300.0, 600.0
ALPHA = 1e-3
GRID = TableGrid(2, 3, 3, thickness_nm=(OWN_NM, T_NM))


def stack(top_nm: float) -> bl.Layered:
    top = bl.Dielectric(1.5, 1.0, film=[{"material": 1.38, "thickness_nm": top_nm}])
    base = bl.Dielectric(1.0, 1.5, film=[{"material": 2.2, "thickness_nm": 200.0}])
    return bl.Layered([top], [bl.Slab(1.0, sigma_a=0.05, sigma_s=0.5)], base)


@pytest.fixture(scope="module")
def tables():
    kw = dict(rel_error=0.5, wavelengths=WL, progress=False)
    return {
        "pfmc": tabulate(stack(OWN_NM), GRID, method="pfmc", min_samples=512, max_samples=512, **kw),
        "adding-doubling": tabulate(stack(OWN_NM), GRID, method="adding-doubling", **kw),
    }


def node_cells(table):
    """(wi, wo, values, errors) of the cells at the node T, values f (no cosine)."""
    wi, wo = lobe_directions(table.grid, len(table.lobes))
    k = list(table.grid.thickness_nm).index(T_NM)
    C = len(table.channels)
    return wi, wo, table.values[:, k].reshape(-1, C), table.stderr[:, k].reshape(-1, C)


def test_pfmc_cells_at_a_node_are_the_model_with_that_top_film(tables):
    wi, wo, v, e = node_cells(tables["pfmc"])
    ref = stack(T_NM).estimate(wi, wo, WL, samples=2048, seed=5, scattered_only=True)
    cos = np.abs(wo[:, 2:])
    se = np.hypot(e, ref.stderr / cos)
    z = np.abs(v - ref.value / cos) / se
    bound = NormalDist().inv_cdf(1.0 - (1.0 - (1.0 - ALPHA) ** (1.0 / z.size)) / 2.0)
    assert np.all(se > 0) and np.all(z < bound), (z.max(), bound)


def test_adding_doubling_cells_at_a_node_are_the_model_with_that_top_film(tables):
    wi, wo, v, e = node_cells(tables["adding-doubling"])
    ref, ref_err = solve(stack(T_NM), WL).eval_with_error(wi, wo, scattered_only=True)
    cos = np.abs(wo[:, 2:])
    want = ref / cos
    tol = e + ref_err / cos + 2.0 * np.finfo(np.float32).eps * np.abs(want)
    assert np.all(np.abs(v - want) <= tol), np.max(np.abs(v - want) - tol)


def table_lobe(tb: TableBSDF, wi: np.ndarray, lobe: int, thickness_nm) -> np.ndarray:
    """The weight of the table's delta lobe `lobe` toward its one direction (weight x pdf:
    its reflectance or transmittance), walking the sampler's mixture from u1 = 0."""
    u = 0.0
    for _ in range(2):
        s = tb.sample(wi[None], np.array([u]), np.array([[0.5, 0.5]]), thickness_nm=thickness_nm)
        if int(s.lobe[0]) == lobe:
            return s.weight[0] * s.pdf[0]
        if not int(s.lobe[0]) & int(Lobe.DELTA):
            break
        u = min(u + s.pdf[0] * (1 + 1e-9) + 1e-12, 1 - 1e-12)
    return np.zeros(len(WL))


@pytest.mark.parametrize("method", ["pfmc", "adding-doubling"])
@pytest.mark.parametrize(("thickness", "top_nm"), [(T_NM, T_NM), (None, OWN_NM)])
@pytest.mark.parametrize("up", [True, False])
def test_delta_lobes_at_a_thickness_are_the_model_with_that_top_film(tables, method, thickness, top_nm, up):
    """At T and at the table's default (the top's own film, thickness None)."""
    t = np.radians(30.0)
    wi = np.array([np.sin(t), 0.0, np.cos(t) if up else -np.cos(t)])
    ref_stack, _ = delta_stack(stack(top_nm).to_dict(), np.array(WL), np.eye(len(WL)))
    R, T, _, _ = ref_stack.solve(wi, -1.0)
    tb = TableBSDF(tables[method])
    got_r = table_lobe(tb, wi, int(Lobe.DELTA_REFLECTION), thickness)
    got_t = table_lobe(tb, wi, int(Lobe.DELTA_TRANSMISSION), thickness)
    assert np.all(T > 0.05) and np.all(R > 0.01)
    np.testing.assert_allclose(got_r, R, rtol=1e-9, atol=0)
    np.testing.assert_allclose(got_t, T, rtol=1e-9, atol=0)
