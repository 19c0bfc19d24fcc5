"""A PFMC table made before estimator version 8 with a thickness axis and a film below the
top holds cells with that film rescaled to each node (the old rule), while the lookup's
delta lobes and the base's exact part now keep the model's own film: reading one warns
(before, it read silently as a mix of the two rules). Tables of version 8, without a
thickness axis, without a film below the top, or made by adding-doubling read quietly."""

from __future__ import annotations

import copy
import warnings

import pytest

import bsdflab as bl
from bsdflab.tables import TableBSDF, TableGrid, tabulate

WL = [450.0, 550.0, 650.0]


def stack(base_film: bool) -> bl.Layered:
    top = bl.Dielectric(1.5, 1.0, film=[{"material": 1.38, "thickness_nm": 300.0}])
    film = [{"material": 2.2, "thickness_nm": 200.0}] if base_film else None
    return bl.Layered([top], [bl.Slab(1.0, sigma_a=0.05, sigma_s=0.5)], bl.Dielectric(1.0, 1.5, film=film))


def table(base_film: bool, thickness=(300.0, 600.0), version=7, method="pfmc"):
    kw = dict(rel_error=0.5, wavelengths=WL, progress=False, method=method)
    if method == "pfmc":
        kw.update(min_samples=8, max_samples=8)
    t = tabulate(stack(base_film), TableGrid(2, 2, 2, thickness_nm=thickness), **kw)
    t = copy.copy(t)
    t.meta = {**t.meta, "estimator_version": version} if method == "pfmc" else dict(t.meta)
    return t


def test_an_old_pfmc_table_with_a_filmed_base_and_a_thickness_axis_warns():
    with pytest.warns(RuntimeWarning, match="estimator version 7.*rescale the films below the top"):
        TableBSDF(table(True))


@pytest.mark.parametrize(
    "kw",
    [
        {"base_film": True, "version": 8},
        {"base_film": True, "thickness": ()},
        {"base_film": False},
        {"base_film": True, "method": "adding-doubling"},
    ],
    ids=["version 8", "no thickness axis", "no film below the top", "adding-doubling"],
)
def test_other_tables_read_quietly(kw):
    t = table(**kw)
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        TableBSDF(t)
