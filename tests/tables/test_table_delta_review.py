"""The tabulated delta lobes against independent references (hand-written incoherent sums
with their own Fresnel; an adversarial review of the delta parts), the core stack's input
checks, and a table with a film-thickness axis read at its default (the top film's total)
against the model itself: the delta lobes give that thickness to the top alone, so a
filmed base keeps its own film (a strict xfail before estimator version 8, when every
boundary took the query's thickness and the base here read 300 nm instead of 200 nm)."""

from __future__ import annotations

import numpy as np
import pytest

import bsdflab as bl
from bsdflab.lobes import Lobe
from bsdflab.tables import TableBSDF, TableGrid, tabulate

TOP = bl.Dielectric(1.5, 1.0, film=[{"material": 1.38, "thickness_nm": 300.0}])
BASE = bl.Dielectric(1.0, 1.5, film=[{"material": 2.2, "thickness_nm": 200.0}])
MODEL = bl.Layered([TOP], [bl.Slab(1.0, sigma_a=0.05, sigma_s=0.0)], BASE)
N = 40_000


@pytest.fixture(scope="module")
def table():
    kw = dict(rel_error=0.5, method="pfmc", min_samples=8, max_samples=8, progress=False)
    return TableBSDF(tabulate(MODEL, TableGrid(2, 3, 3, thickness_nm=(200.0, 300.0, 400.0)), **kw))


def table_lobe(tb, wi, lobe):
    u = 0.0
    for _ in range(2):
        s = tb.sample(wi[None], np.array([u]), np.array([[0.5, 0.5]]))
        if int(s.lobe[0]) == lobe:
            return s.weight[0] * s.pdf[0]
        if not int(s.lobe[0]) & int(Lobe.DELTA):
            break
        u = min(u + s.pdf[0] * (1 + 1e-9) + 1e-12, 1 - 1e-12)
    return np.zeros(3)


@pytest.mark.parametrize(("side", "lobe"), [(1.0, int(Lobe.DELTA_TRANSMISSION)), (-1.0, int(Lobe.DELTA_REFLECTION))])
def test_default_thickness_keeps_the_base_film(table, side, lobe):
    t = np.radians(30.0)
    wi = np.array([np.sin(t), 0.0, side * np.cos(t)])
    s = MODEL.sample(np.tile(wi, (N, 1)), seed=3)  # the model as it is (own films)
    w = np.where((np.asarray(s.lobe) == lobe)[:, None], s.weight, 0.0)
    mean, se = w.mean(axis=0), w.std(axis=0, ddof=1) / np.sqrt(N)
    ours = table_lobe(table, wi, lobe)  # the table at its default thickness (query -1)
    assert np.all(np.abs(ours - mean) < 5 * se + 2e-3), (ours, mean, se)


@pytest.mark.parametrize("sigma_t", [-1.0, float("nan")])
def test_delta_stack_rejects_bad_extinction(sigma_t):
    """A negative sigma_t transmitted 2.54 at normal incidence through a glass plate
    (energy gain) and a NaN one silently dropped to R = r_top, T = 0: both are refused."""
    top, base = bl.Dielectric(1.5, 1.0).render_core()[0], bl.Dielectric(1.0, 1.5).render_core()[0]
    with pytest.raises(ValueError):
        bl._core.TableDeltaStack([top, base], thickness_um=[1.0], sigma_t=[[sigma_t]])


# Independent references (hand-written incoherent sums, own Fresnel): these pass.
def _fres(ci, n1, n2):
    ci = abs(ci)
    s2 = (n1 / n2) ** 2 * (1 - ci * ci)
    if s2 >= 1:
        return 1.0, 0.0
    ct = np.sqrt(1 - s2)
    rs = (n1 * ci - n2 * ct) / (n1 * ci + n2 * ct)
    rp = (n2 * ci - n1 * ct) / (n2 * ci + n1 * ct)
    return 0.5 * (rs * rs + rp * rp), ct


def _solve(model, wi):
    from bsdflab.tables.delta import delta_stack

    st, _ = delta_stack(model.to_dict(), np.array([550.0]), np.eye(1))
    R, T, _, _ = st.solve(np.asarray(wi, float), -1.0)
    return R[0], T[0]


@pytest.mark.parametrize("theta", [0.0, 40.0, 70.0, 85.0])
@pytest.mark.parametrize("side", [1.0, -1.0])
def test_glass_plate_matches_incoherent_sum(theta, side):
    d, st = 2.0, 0.3
    plate = bl.Layered([bl.Dielectric(1.5, 1.0)], [bl.Slab(d, sigma_a=0.2, sigma_s=0.1)], bl.Dielectric(1.0, 1.5))
    t = np.radians(theta)
    r, ct = _fres(np.cos(t), 1.0, 1.5)
    a = np.exp(-st * d / ct)
    R = r + (1 - r) ** 2 * r * a * a / (1 - r * r * a * a)
    T = (1 - r) ** 2 * a / (1 - r * r * a * a)
    assert _solve(plate, [np.sin(t), 0.0, side * np.cos(t)]) == pytest.approx((R, T), rel=1e-10, abs=1e-14)


@pytest.mark.parametrize("theta", [0.0, 30.0, 60.0, 80.0])
def test_glass_over_water_from_below_with_tir(theta):
    m = bl.Layered([bl.Dielectric(1.5, 1.0)], [bl.Slab(1.0, sigma_a=0.1, sigma_s=0.2)], bl.Dielectric(1.33, 1.5))
    t = np.radians(theta)
    r0, _ = _fres(np.cos(t), 1.33, 1.5)
    s = np.sin(t) * 1.33 / 1.5
    cg = np.sqrt(1 - s * s)
    r1, ca = _fres(cg, 1.5, 1.0)
    a = np.exp(-0.3 / cg)
    R = r0 + (1 - r0) ** 2 * r1 * a * a / (1 - r0 * r1 * a * a)
    T = (1 - r0) * (1 - r1) * a / (1 - r0 * r1 * a * a) * 1.33**2  # radiance mode
    assert _solve(m, [np.sin(t), 0.0, -np.cos(t)]) == pytest.approx((R, T), rel=1e-10, abs=1e-14)
