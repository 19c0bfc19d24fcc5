"""BSDF tables: tabulation accuracy, lookup, sampling, the thickness axis, files, Ctrl-C
and bad input (the file format itself: test_table_format.py).

Significance and bounds
-----------------------
Statistical checks use family-wise significance ALPHA = 0.01, Sidak-corrected over the
comparisons of one test: z_n = Phi^-1(1 - (1 - (1 - ALPHA)^(1/n)) / 2) for n two-sided
comparisons (4.24 for n = 450). Sidak holds for correlated normal z's (Sidak 1967), so
the three channels of one direction may count as three comparisons.

Interpolation error (lookup is multilinear over theta_i, theta_o, phi in radians, see
core/src/table_bsdf.cpp). Linear interpolation of g on [a, b] errs by
|g(x) - L(x)| = |g''(xi)| (x - a)(b - x) / 2 <= h^2 / 8 max|g''|. The multilinear
operator is I1 I2 I3 with each I_k a convex combination (sup-norm 1), so
f - I1 I2 I3 f = (f - I1 f) + I1 (f - I2 f) + I1 I2 (f - I3 f) gives, at a query x in the
cell box B,
    |f(x) - I f(x)| <= sum_k (x_k - a_k)(b_k - x_k) / 2 * max_B |d^2 f / dx_k^2|
                    <= sum_k h_k^2 / 8 * max_B |d^2 f / dx_k^2|.
Outside the node range of an axis (theta < h/2: nodes are cell centres) the core clamps
to the end node; I_k is then "take the end node", still of norm 1, and its term is
first order: |x_k - node| * max |d f / dx_k| over the segment.
"""
from __future__ import annotations

import itertools
import os
import re
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

import bsdflab as bl
from bsdflab.cli.main import main as cli_main
from bsdflab.tables import TableBSDF, TableGrid, tabulate, write_table
from bsdflab.testing import albedo_sampled, albedo_uniform, bsdf_chi2, sidak_z_limit
from support.cli import interruptible, wait_for_cpu
from support.liveness import HANG_S

ALPHA = 0.01
WL = [450.0, 550.0, 650.0]  # spectral tables: 27x cheaper walks than 81-wavelength RGB
FLOAT32_REL = 2.0 ** -23   # stored values are float32 (2^-24), plus double arithmetic
BSDFLAB = [sys.executable, "-m", "bsdflab.cli.main"]


def z_limit(n: int, alpha: float = ALPHA) -> float:
    return sidak_z_limit(alpha, n)


def sph(theta, phi) -> np.ndarray:
    theta, phi = np.broadcast_arrays(np.asarray(theta, float), np.asarray(phi, float))
    return np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], -1)


def angles(wi, wo):
    """(theta_i, theta_o, |phi_o - phi_i| in [0, pi]) as the core computes them."""
    d = np.abs(np.arctan2(wo[:, 1], wo[:, 0]) - np.arctan2(wi[:, 1], wi[:, 0]))
    return (np.arccos(np.clip(wi[:, 2], -1, 1)), np.arccos(np.clip(np.abs(wo[:, 2]), 0, 1)),
            np.where(d > np.pi, 2 * np.pi - d, d))


def axis_weights(x, nodes):
    """Lower node and weight of the upper one, clamped to the end nodes (as the core)."""
    u = np.clip((x - nodes[0]) / (nodes[1] - nodes[0]), 0, len(nodes) - 1)
    i0 = np.minimum(np.floor(u).astype(int), len(nodes) - 2)
    return i0, u - i0


def corners(grid: TableGrid, wi, wo):
    """The 8 corner nodes (N, 8, 3) of each query's cell and their weights (N, 8)."""
    ax = [axis_weights(x, n) for x, n in zip(angles(wi, wo), (grid.theta_i, grid.theta_o, grid.phi), strict=True)]
    idx, w = [], []
    for bits in itertools.product((0, 1), repeat=3):
        idx.append(np.stack([i0 + b for (i0, _), b in zip(ax, bits, strict=True)], -1))
        w.append(np.prod([t if b else 1 - t for (_, t), b in zip(ax, bits, strict=True)], axis=0))
    return np.stack(idx, 1), np.stack(w, 1)


def at(array, idx):
    return array[idx[..., 0], idx[..., 1], idx[..., 2]]


def second_differences(V):
    """|f(x+h) - 2 f(x) + f(x-h)| at every node along theta_i, theta_o, phi (~ h^2 |f''|).
    At the theta ends the neighbour's value is reused; in phi f is even about 0 and pi."""
    out = []
    for k in (0, 1):
        v = np.moveaxis(V, k, 0)
        d = np.empty_like(v)
        d[1:-1] = v[2:] - 2 * v[1:-1] + v[:-2]
        d[0], d[-1] = d[1], d[-2]
        out.append(np.abs(np.moveaxis(d, 0, k)))
    p = np.concatenate([V[:, :, 1:2], V, V[:, :, -2:-1]], axis=2)
    out.append(np.abs(p[:, :, 2:] - 2 * p[:, :, 1:-1] + p[:, :, :-2]))
    return out


def table_interpolation_bound(grid, D2, wi, wo, idx):
    """Interpolation bound on f (no cosine), (N, C), from the table's own second
    differences: sum_k t_k (1 - t_k) / 2 * max over the cell's corners of |D2_k|
    (= (x - a)(b - x)/2 |f''| with f'' ~ D2 / h^2; at most max|D2_k| / 8)."""
    bound = 0.0
    for k, (x, nodes) in enumerate(zip(angles(wi, wo), (grid.theta_i, grid.theta_o, grid.phi), strict=True)):
        _, t = axis_weights(x, nodes)
        bound = bound + (t * (1 - t) / 2)[:, None] * at(D2[k], idx).max(axis=1)
    return bound


@pytest.fixture(scope="module")
def xeno():
    """The xenopeltis preset tabulated at three wavelengths on a small grid.

    PFMC walk contributions are heavy-tailed (NEE through the alpha = 0.08 top; worst at
    650 nm, where melanin absorbs least): with ~100 walks a cell's mean is usually low and
    its standard error underestimated (z up to 7 against a 40k-walk reference), so every
    cell gets min_samples = 4096, where the normal approximation holds (max |z| 3.3-4.2
    over all 1620 node values, sum z^2 / n 0.92-1.10, three seeds). ~2.5 s."""
    model = bl.presets.xenopeltis(samples=64)
    table = tabulate(model, TableGrid(6, 10, 9), rel_error=0.03, wavelengths=WL,
                     min_samples=4096, seed=1, progress=False)
    return model, table, TableBSDF(table)


@pytest.fixture(scope="module")
def film_model():
    """A deterministic model with a thin film (so thickness matters) that also transmits."""
    return bl.RoughDielectric(0.3, int_ior=1.55, ext_ior=1.0,
                              film=[{"material": 1.83, "thickness_nm": 400.0}])


# -- 1. analytic models ---------------------------------------------------------------------

def test_01_diffuse_table_is_exact_to_float32():
    """f of a Lambertian is constant, so interpolation (and the clamped extrapolation
    near normal and grazing) is exact; only float32 storage rounds: |T - A| <= 2^-23 A."""
    model = bl.Diffuse(0.6)
    tb = TableBSDF(tabulate(model, TableGrid(3, 4, 2), progress=False))
    rng = np.random.default_rng(1)
    n = 500
    wi = sph(np.arccos(rng.random(n)), rng.uniform(0, 2 * np.pi, n))       # whole hemisphere
    wo = sph(np.arccos(rng.uniform(-1, 1, n)), rng.uniform(0, 2 * np.pi, n))  # and below
    table, exact = tb.eval(wi, wo), model.eval(wi, wo)
    assert np.all(np.abs(table - exact) <= FLOAT32_REL * np.abs(exact) + 1e-300)
    assert np.all(table[wo[:, 2] < 0] == 0) and np.all(table[wo[:, 2] > 0] > 0)


def fd_interpolation_bound(f, grid: TableGrid, x: np.ndarray, sub: int = 9, margin: float = 1.1):
    """Pointwise bound (module docstring) on |f - I f| at queries x (N, 3), with the
    derivatives of the analytic f estimated by finite differences on a sub x sub x sub
    grid spanning each query's cell box (spacing h/8 for sub = 9), extended one step
    outward for the central differences. The sampled max can miss the true max between
    sub-grid points by O(spacing^2 |f''''|): `margin` (10 %) covers it.
    Returns (bound (N, C), max |f| over the box (N, C))."""
    nodes = (grid.theta_i, grid.theta_o, grid.phi)
    n = len(x)
    lo, hi, clamped = np.empty((n, 3)), np.empty((n, 3)), np.zeros((n, 3), bool)
    for k, nd in enumerate(nodes):
        i0, _ = axis_weights(x[:, k], nd)
        outside = (x[:, k] < nd[0]) | (x[:, k] > nd[-1])
        end = np.where(x[:, k] < nd[0], nd[0], nd[-1])
        lo[:, k] = np.where(outside, np.minimum(x[:, k], end), nd[i0])
        hi[:, k] = np.where(outside, np.maximum(x[:, k], end), nd[i0 + 1])
        clamped[:, k] = outside
    step = np.maximum(hi - lo, 1e-9) / (sub - 1)
    offsets = np.arange(-1, sub + 1)                       # one step beyond each end
    g = [lo[:, k, None] + step[:, k, None] * offsets for k in range(3)]
    m = sub + 2
    mesh = (g[0][:, :, None, None], g[1][:, None, :, None], g[2][:, None, None, :])
    ti, to, ph = (np.broadcast_to(a, (n, m, m, m)).ravel() for a in mesh)
    F = f(ti, to, ph).reshape(n, m, m, m, -1)

    def shifted(k, s):  # F moved by s along axis k, the other axes on the box
        return F[tuple([slice(None)] + [slice(1 + s, m - 1 + s) if j == k else slice(1, m - 1)
                                        for j in range(3)])]

    bound = 0.0
    for k in range(3):
        h = step[:, k, None]
        d2 = np.abs(shifted(k, 1) - 2 * shifted(k, 0) + shifted(k, -1)).max(axis=(1, 2, 3)) / h**2
        d1 = np.abs(shifted(k, 1) - shifted(k, -1)).max(axis=(1, 2, 3)) / (2 * h)
        inner = ((x[:, k] - lo[:, k]) * (hi[:, k] - x[:, k]) / 2)[:, None] * d2
        outer = (hi[:, k] - lo[:, k])[:, None] * d1
        bound = bound + margin * np.where(clamped[:, k, None], outer, inner)
    return bound, np.abs(shifted(0, 0)).max(axis=(1, 2, 3))


def test_02_rough_conductor_within_the_interpolation_bound():
    """GGX conductor (alpha 0.4, gold) on the default grid 12 x 24 x 13 at 250 random
    directions with theta_i, theta_o < 80 deg (the near-normal clamped band included):
    |T - A| / cos theta_o <= sum_k (x_k - a_k)(b_k - x_k)/2 max_cell|f_kk| (first order
    in the clamped band) + 2^-23 max|f|, derivatives by finite differences of the analytic
    model over each query's cell (fd_interpolation_bound). Pointwise, every channel."""
    model = bl.RoughConductor(0.4, material="Au")
    grid = TableGrid()
    table = tabulate(model, grid, progress=False)
    tb = TableBSDF(table)
    rng = np.random.default_rng(2)
    n, top = 250, np.radians(80.0)
    wi = sph(rng.uniform(0, top, n), rng.uniform(0, 2 * np.pi, n))
    wo = sph(rng.uniform(0, top, n), rng.uniform(0, 2 * np.pi, n))

    def f(ti, to, ph):  # the analytic BSDF value without the cosine
        b = sph(to, ph)
        return model.eval(sph(ti, 0.0), b) / np.abs(b[:, 2:3])

    # At the nodes the table is the model (to float32): tabulation is exact there.
    k = rng.integers(0, [grid.n_theta_i, grid.n_theta_o, grid.n_phi], size=(50, 3))
    node_f = f(grid.theta_i[k[:, 0]], grid.theta_o[k[:, 1]], grid.phi[k[:, 2]])
    stored = table.values[0, 0, k[:, 0], k[:, 1], k[:, 2]]
    assert np.all(np.abs(stored - node_f) <= 2.0 ** -24 * np.abs(node_f))

    bound, f_max = fd_interpolation_bound(f, grid, np.stack(angles(wi, wo), 1))
    cos_o = np.abs(wo[:, 2:3])
    error = np.abs(tb.eval(wi, wo) - model.eval(wi, wo)) / cos_o
    ratio = error / (bound + FLOAT32_REL * f_max)
    assert ratio.max() <= 1.0, f"interpolation error exceeds its bound: max ratio {ratio.max():.3f}"
    # ...and the bound is not vacuous (measured: max 0.88, median 0.66), so a lookup
    # that interpolated the wrong cells or axes would break it.
    assert ratio.max() > 0.3, ratio.max()


# -- 2. layered model vs PFMC ---------------------------------------------------------------

def test_03_layered_table_matches_pfmc_off_grid(xeno):
    """xenopeltis table (6 x 10 x 9, spectral) vs PFMC eval_with_error (8000 walks) at 150
    random directions inside the node range (theta from the first node to min(last node,
    80 deg)), full eval (the table adds the top interface's reflection exactly), 3 channels:
        |T - P| <= z_450 sqrt(sigma_T^2 + sigma_P^2) + cos theta_o * B,
    sigma_T = sqrt(sum_j w_j^2 sigma_j^2) the interpolated table noise (cells independent),
    z_450 = 4.24 (Sidak, ALPHA), B the interpolation bound from the table's own second
    differences (table_interpolation_bound; noise only inflates it). Without B the test
    fails (max z 5-6): the interpolation error is real and B accounts for it (measured max
    ratio 0.66 over three seeds)."""
    model, table, tb = xeno
    grid = table.grid
    V, S = table.values[0, 0].astype(float), table.stderr[0, 0].astype(float)
    rng = np.random.default_rng(3)
    n = 150
    top = np.radians(80.0)
    wi = sph(rng.uniform(grid.theta_i[0], min(grid.theta_i[-1], top), n), rng.uniform(0, 2 * np.pi, n))
    wo = sph(rng.uniform(grid.theta_o[0], min(grid.theta_o[-1], top), n), rng.uniform(0, 2 * np.pi, n))
    idx, w = corners(grid, wi, wo)
    cos_o = wo[:, 2:3]

    looked_up = tb.eval(wi, wo)
    # The lookup is the documented one: multilinear table part + the exact top reflection.
    direct = bl.from_dict(table.model).exact_part.eval(wi, wo, wavelengths=WL)
    replica = np.einsum("nk,nkc->nc", w, at(V, idx)) * cos_o + direct
    assert np.allclose(looked_up, replica, rtol=1e-12, atol=0)

    ref, ref_err = model.eval_with_error(wi, wo, wavelengths=WL, samples=8000, seed=13)
    sigma_t = np.sqrt(np.einsum("nk,nkc->nc", w**2, at(S, idx) ** 2)) * cos_o
    interp = table_interpolation_bound(grid, second_differences(V), wi, wo, idx) * cos_o
    tol = z_limit(looked_up.size) * np.hypot(sigma_t, ref_err) + interp
    ratio = np.abs(looked_up - ref) / tol
    assert ratio.max() < 1.0, f"max |T - P| / tolerance = {ratio.max():.3f}"


# -- 3. sampling ----------------------------------------------------------------------------

@pytest.mark.parametrize("theta_deg", [0.0, 40.0, 85.0])
def test_04_table_sampling_chi2(xeno, theta_deg):
    """sample() follows pdf() (chi-square, 200k samples, Sidak over the 3 angles; 85 deg
    lies beyond the last theta_i node, 82.5). Quadrature order 10: the exact top lobe
    (GGX alpha 0.08) is too peaked near grazing for the default 5 (with 5 the bare top
    interface itself is rejected at 85 deg: pdf integral 0.981 vs 0.965 by 20 nodes)."""
    _, _, tb = xeno
    wi = sph(np.radians(theta_deg), 0.0)
    test = bsdf_chi2(tb, wi, sample_count=200_000, test_count=3, seed=4, quadrature_order=10)
    assert test.run(), test.message


def test_05_white_furnace(xeno):
    """At theta_i = 30 and 60 deg (between theta_i nodes), 3 channels, z = z_6 (Sidak):
    (a) the table's mean sample weight equals the uniform integral of its eval:
        |A_s - A_u| <= z sqrt(se_s^2 + se_u^2);
    (b) it agrees with the source model's albedo (mean PFMC sample weight) over the node
        range theta_o in [h/2, 90 deg - h/2], where the interpolation bound applies (the
        lookup extrapolates constantly outside it; both estimators are masked to the same
        wo region, which keeps them unbiased for that partial integral):
        |A_T - A_M| <= z sqrt(se_T^2 + se_M^2 + s_noise^2) + int B cos dw,
        s_noise^2 = sum_j c_j^2 sigma_j^2 with c_j = int w_j cos dw (the table albedo is
        linear in the cells), B the pointwise bound of test 03; both integrals by 200k
        uniform hemisphere directions (+3 standard errors for the bound's integral)."""
    model, table, tb = xeno
    grid = table.grid
    V, S = table.values[0, 0].astype(float), table.stderr[0, 0].astype(float)
    D2 = second_differences(V)
    lo, hi = grid.theta_o[0], grid.theta_o[-1]
    z = z_limit(2 * len(WL))
    n = 200_000

    def in_node_range(s):
        theta_o = np.arccos(np.clip(np.abs(s.wo[:, 2]), 0, 1))
        keep = (s.lobe != 0) & (s.wo[:, 2] > 0) & (theta_o >= lo) & (theta_o <= hi)
        w = np.where(keep[:, None], s.weight, 0.0)
        return w.mean(axis=0), w.std(axis=0, ddof=1) / np.sqrt(len(w))

    rng = np.random.default_rng(5)
    wo = sph(np.arccos(rng.random(n)), rng.uniform(0, 2 * np.pi, n))  # uniform, pdf 1/(2 pi)
    for k, theta in enumerate(np.radians([30.0, 60.0])):
        wi1 = sph(theta, 0.0)
        sampled = albedo_sampled(tb, wi1, n=n, seed=10 + k)
        uniform = albedo_uniform(tb, wi1, n=2 * n, seed=20 + k)
        gap = np.abs(sampled.mean - uniform.mean)
        assert np.all(gap <= z * np.hypot(sampled.stderr, uniform.stderr)), (theta, sampled, uniform)

        a_t, se_t = in_node_range(tb.sample(np.tile(wi1, (n, 1)), seed=30 + k))
        a_m, se_m = in_node_range(model.sample(np.tile(wi1, (n, 1)), seed=40 + k, wavelengths=WL))
        wi = np.tile(wi1, (n, 1))
        idx, w = corners(grid, wi, wo)
        theta_o = angles(wi, wo)[1]
        weight = 2 * np.pi * wo[:, 2] * ((theta_o >= lo) & (theta_o <= hi))  # cos / pdf, masked
        flat = np.ravel_multi_index((idx[..., 0], idx[..., 1], idx[..., 2]), V.shape[:3])
        c = np.bincount(flat.ravel(), (w * weight[:, None] / n).ravel(), minlength=V[..., 0].size)
        s_noise = np.sqrt(c**2 @ S.reshape(-1, len(WL)) ** 2)
        b = table_interpolation_bound(grid, D2, wi, wo, idx) * weight[:, None]
        b_int = b.mean(axis=0) + 3 * b.std(axis=0) / np.sqrt(n)
        tol = z * np.sqrt(se_t**2 + se_m**2 + s_noise**2) + b_int
        assert np.all(np.abs(a_t - a_m) <= tol), (np.degrees(theta), a_t, a_m, tol)


# -- 4. thickness axis ----------------------------------------------------------------------

def random_pairs(n, seed, both_sides=True):
    rng = np.random.default_rng(seed)
    wi = sph(np.arccos(rng.random(n)), rng.uniform(0, 2 * np.pi, n))
    wo = sph(np.arccos(rng.uniform(-1 if both_sides else 0, 1, n)), rng.uniform(0, 2 * np.pi, n))
    return wi, wo


def test_06_thickness_axis_interpolates_linearly(film_model):
    """Film model (deterministic, reflects and transmits), nodes 300/400/500 nm: at a node
    the table equals a one-node table of that thickness bit for bit; between nodes it is
    the linear blend (so between the two); outside it clamps; None means the model's 400."""
    grid = dict(n_theta_i=4, n_theta_o=6, n_phi=5)
    three = TableBSDF(tabulate(film_model, TableGrid(**grid, thickness_nm=(300, 400, 500)), progress=False))
    one = {t: TableBSDF(tabulate(film_model, TableGrid(**grid, thickness_nm=(t,)), progress=False))
           for t in (300.0, 400.0, 500.0)}
    wi, wo = random_pairs(200, 6)
    at_node = {t: three.eval(wi, wo, thickness_nm=t) for t in one}
    for t in one:
        np.testing.assert_array_equal(at_node[t], one[t].eval(wi, wo))
    assert not np.allclose(at_node[300.0], at_node[400.0])  # the axis matters
    for t, (a, b) in {350.0: (300.0, 400.0), 330.0: (300.0, 400.0), 480.0: (400.0, 500.0)}.items():
        s = (t - a) / (b - a)
        v = three.eval(wi, wo, thickness_nm=t)
        np.testing.assert_allclose(v, (1 - s) * at_node[a] + s * at_node[b], rtol=1e-12, atol=1e-300)
        assert np.all(v >= np.minimum(at_node[a], at_node[b]) * (1 - 1e-12))
        assert np.all(v <= np.maximum(at_node[a], at_node[b]) * (1 + 1e-12))
    np.testing.assert_array_equal(three.eval(wi, wo, thickness_nm=250.0), at_node[300.0])
    np.testing.assert_array_equal(three.eval(wi, wo, thickness_nm=600.0), at_node[500.0])
    np.testing.assert_array_equal(three.eval(wi, wo), at_node[400.0])


def test_07_table_without_thickness_axis_ignores_thickness(film_model):
    """No axis: the table is the model at its own film (400 nm) whatever thickness asks."""
    tb = TableBSDF(tabulate(film_model, TableGrid(4, 6, 5), progress=False))
    wi, wo = random_pairs(100, 7)
    base = tb.eval(wi, wo)
    for t in (0.0, 250.0, 400.0, 900.0):
        np.testing.assert_array_equal(tb.eval(wi, wo, thickness_nm=t), base)
        np.testing.assert_array_equal(tb.pdf(wi, wo, thickness_nm=t), tb.pdf(wi, wo))


def test_08_layered_thickness_axis_and_exact_top():
    """Layered (split) tables: the exact top reflection follows the film the table part
    describes. Several nodes: it is evaluated at the query's thickness and the table part
    blends linearly. No axis: thickness is ignored, top included (it used to follow the
    query: a table at 400 nm plus a top at the asked thickness). One node: that node's."""
    model = bl.presets.xenopeltis(samples=16)
    top = model.interfaces[0]
    wi, wo = random_pairs(60, 8, both_sides=False)

    def part(tb, t):  # the tabulated (scattered) part alone
        return tb.eval(wi, wo, thickness_nm=t) - top.eval(wi, wo, wavelengths=WL, thickness_nm=t)

    kw = dict(rel_error=0.5, wavelengths=WL, min_samples=16, max_samples=16, progress=False)
    three = TableBSDF(tabulate(model, TableGrid(3, 4, 3, (300.0, 400.0, 500.0)), **kw))
    np.testing.assert_allclose(part(three, 350.0), 0.5 * (part(three, 300.0) + part(three, 400.0)),
                               rtol=1e-9, atol=1e-12)

    none = TableBSDF(tabulate(model, TableGrid(3, 4, 3), **kw))
    for t in (0.0, 250.0, 700.0):
        np.testing.assert_array_equal(none.eval(wi, wo, thickness_nm=t), none.eval(wi, wo))

    single = tabulate(model, TableGrid(3, 4, 3, (350.0,)), **kw)
    tb = TableBSDF(single)
    np.testing.assert_array_equal(tb.eval(wi, wo, thickness_nm=600.0), tb.eval(wi, wo))
    idx, w = corners(single.grid, wi, wo)
    table_part = np.einsum("nk,nkc->nc", w, at(single.values[0, 0].astype(float), idx)) * wo[:, 2:3]
    exact_top = top.eval(wi, wo, wavelengths=WL, thickness_nm=350.0)
    np.testing.assert_allclose(tb.eval(wi, wo), table_part + exact_top, rtol=1e-12, atol=1e-15)


# -- 5. files and channels ------------------------------------------------------------------

def test_09_round_trip_through_a_file(tmp_path, film_model, xeno):
    """TableBSDF(path) answers exactly as TableBSDF(table), for an RGB two-lobe table with
    a thickness axis and for the spectral layered one; from_dict({'type': 'table', ...})."""
    wi, wo = random_pairs(300, 9)
    thickness = np.random.default_rng(9).uniform(250, 550, len(wi))
    tables = {"film.exr": tabulate(film_model, TableGrid(4, 6, 5, (300.0, 500.0)), progress=False),
              "xeno.exr": xeno[1]}
    for name, table in tables.items():
        path = tmp_path / name
        write_table(path, table)
        mem, disk = TableBSDF(table), TableBSDF(path)
        np.testing.assert_array_equal(disk.eval(wi, wo, thickness_nm=thickness),
                                      mem.eval(wi, wo, thickness_nm=thickness))
        np.testing.assert_array_equal(disk.pdf(wi, wo, thickness_nm=thickness),
                                      mem.pdf(wi, wo, thickness_nm=thickness))
        a, b = disk.sample(wi, seed=3), mem.sample(wi, seed=3)
        np.testing.assert_array_equal(a.wo, b.wo)
        np.testing.assert_array_equal(a.weight, b.weight)
        d = bl.from_dict({"type": "table", "path": str(path)})
        assert isinstance(d, TableBSDF) and d.to_dict() == {"type": "table", "path": str(path)}
        np.testing.assert_array_equal(d.eval(wi, wo), mem.eval(wi, wo))
        with pytest.raises(ValueError, match="write it to a file"):
            mem.to_dict()
    assert sorted(os.listdir(tmp_path)) == ["film.exr", "xeno.exr"]


def test_10_spectral_table_channels():
    """A spectral table answers at its own wavelengths (None or exactly those) and equals
    the model there at the nodes; any other wavelengths are a ValueError, as are
    wavelengths for an RGB table."""
    model = bl.RoughConductor(0.4, material="Au")
    table = tabulate(model, TableGrid(4, 6, 5), wavelengths=WL, progress=False)
    assert table.channels == ("450", "550", "650")
    tb = TableBSDF(table)
    g = table.grid
    wi = sph(g.theta_i[[0, 1, 3]], 0.0)
    wo = sph(g.theta_o[[2, 5, 0]], g.phi[[1, 4, 0]])
    v = tb.eval(wi, wo)
    np.testing.assert_array_equal(tb.eval(wi, wo, wavelengths=WL), v)
    np.testing.assert_allclose(v, model.eval(wi, wo, wavelengths=WL), rtol=FLOAT32_REL)
    for bad in ([450.0, 550.0], [450.0, 550.0, 651.0], [550.0, 450.0, 650.0], 550.0):
        with pytest.raises(ValueError, match="wavelengths must be None or exactly"):
            tb.eval(wi, wo, wavelengths=bad)
        with pytest.raises(ValueError, match="wavelengths must be None or exactly"):
            tb.sample(wi, wavelengths=bad)
        with pytest.raises(ValueError, match="wavelengths must be None or exactly"):
            tb.pdf(wi, wo, wavelengths=bad)
    rgb = TableBSDF(tabulate(model, TableGrid(2, 2, 2), progress=False))
    with pytest.raises(ValueError, match="wavelengths must be None or exactly"):
        rgb.eval(wi, wo, wavelengths=WL)


# -- 6. Ctrl-C ------------------------------------------------------------------------------

def test_11_interrupted_tabulation_leaves_nothing(tmp_path):
    """SIGINT ~1 s into a real `bsdflab tabulate` (default grid, minutes of work): the
    process stops promptly with status 130 and one line (not an abort, not a traceback),
    no output file, no temporary file, nothing in the cache folder."""
    out_dir, cache = tmp_path / "out", tmp_path / "cache"
    out_dir.mkdir()
    out = out_dir / "x.exr"
    env = dict(os.environ, BSDFLAB_CACHE_DIR=str(cache), BSDFLAB_THREADS="2")
    with interruptible([*BSDFLAB, "tabulate", "--preset", "xenopeltis", "--method", "pfmc", "--out", str(out)],
                       stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env) as proc:
        err = bytearray()
        started = threading.Event()

        def read():  # the progress bar on stderr says the tabulation itself has begun
            while chunk := os.read(proc.stderr.fileno(), 4096):
                err.extend(chunk)
                if b"tabulating" in err:
                    started.set()

        reader = threading.Thread(target=read, daemon=True)
        reader.start()
        assert started.wait(HANG_S), f"tabulation never started: {err.decode(errors='replace')}"
        wait_for_cpu(proc, 1.0, err.decode(errors="replace"))  # inside the tabulation, at any load
        proc.send_signal(signal.SIGINT)
        sent = time.monotonic()
        rc = proc.wait(timeout=HANG_S)   # a hang guard; the latency is printed, not asserted
        print(f"stopped {time.monotonic() - sent:.2f} s after SIGINT")
    reader.join(HANG_S)
    text = err.decode(errors="replace")
    assert rc != 0
    assert rc not in (-signal.SIGABRT, -signal.SIGSEGV) and "terminate called" not in text, (rc, text[-2000:])
    assert rc == 130 and "bsdflab tabulate: interrupted" in text and "Traceback" not in text, (rc, text[-2000:])
    assert os.listdir(out_dir) == []
    assert not cache.exists() or os.listdir(cache) == []


# -- 7. bad input ---------------------------------------------------------------------------

@pytest.mark.parametrize("kwargs, match", [
    (dict(rel_error=0.0), "rel_error must be >"),
    (dict(rel_error=-0.1), "rel_error must be >"),
    (dict(rel_error=1.0001), "rel_error must be <="),
    (dict(rel_error=float("nan")), "rel_error must be finite"),
    (dict(min_samples=100, max_samples=10), "max_samples .* must be >= min_samples"),
    (dict(min_samples=0), "min_samples must be an integer"),
    (dict(max_samples=2.5), "max_samples must be an integer"),
    (dict(wavelengths=[500.0, 500.0]), "distinct"),
    (dict(wavelengths=[-500.0]), "wavelengths must be >"),
])
def test_12_bad_tabulation_arguments(kwargs, match):
    with pytest.raises(ValueError, match=match):
        tabulate(bl.Diffuse(0.5), TableGrid(2, 2, 2), progress=False, **kwargs)


@pytest.mark.parametrize("args, match", [
    ((1, 4, 4), "n_theta_i"), ((4, 1, 4), "n_theta_o"), ((4, 4, 1), "n_phi"),
    ((4, 4, 0), "n_phi"), ((4.0, 4, 4), "n_theta_i"), ((4, 4, 513), "n_phi"),
    ((4, 4, 4, (-1.0,)), "thickness_nm"), ((4, 4, 4, (400.0, 300.0)), "thickness_nm"),
    ((4, 4, 4, (300.0, 300.0)), "thickness_nm"), ((4, 4, 4, (float("nan"),)), "thickness_nm"),
    ((2, 4, 3, [[1.0]]), "thickness_nm must be 1-dimensional"),  # the slow fuzz: was a TypeError
])
def test_13_bad_grids(args, match):
    with pytest.raises(ValueError, match=match):
        TableGrid(*args)


def test_14_bad_models_and_tables(tmp_path):
    for model in ("diffuse", {"type": "diffuse"}, None, bl.Diffuse(0.5).to_dict()):
        with pytest.raises(ValueError, match="model must be a bsdflab BSDF"):
            tabulate(model, TableGrid(2, 2, 2), progress=False)
    with pytest.raises(ValueError, match="give a table"):
        TableBSDF()
    with pytest.raises(ValueError, match="does not exist"):
        TableBSDF(tmp_path / "missing.exr")
    # rel_error = 1 is the inclusive end of the range
    assert tabulate(bl.Diffuse(0.5), TableGrid(2, 2, 2), rel_error=1.0, progress=False).check() is None


@pytest.mark.parametrize("argv, match", [
    (["--rel-error", "0"], "rel_error must be >"),
    (["--rel-error", "1.5"], "rel_error must be <="),
    (["--theta-i", "1"], "n_theta_i"),
    (["--phi", "1"], "n_phi"),
    (["--thickness", "400", "300"], "thickness_nm"),
    (["--thickness", "-5"], "thickness_nm"),
    (["--min-samples", "100", "--max-samples", "10"], "max_samples"),
    (["--wavelengths", "500", "500"], "distinct"),
    (["--preset", "no-such-snake"], "unknown preset"),
    (["--json", "{not json"], "not valid JSON"),
    (["--no-cache"], "--no-cache needs --out"),
])
def test_15_cli_bad_input_exits_2(tmp_path, capsys, argv, match):
    cache = tmp_path / "cache"
    rc = cli_main(["tabulate", "--quiet", "--cache-dir", str(cache), *argv])
    err = capsys.readouterr().err
    assert rc == 2 and err.startswith("bsdflab tabulate: error:") and re.search(match, err), err
    assert not cache.exists() or os.listdir(cache) == []


def test_16_cli_bad_input_as_a_process(tmp_path):
    """The real command line: a bad value and an unparsable one both exit 2 with a message."""
    env = dict(os.environ, BSDFLAB_CACHE_DIR=str(tmp_path))
    for argv, match in ((["--rel-error", "-1"], "rel_error must be >"),
                        (["--theta-o", "many"], "invalid int value")):
        r = subprocess.run([*BSDFLAB, "tabulate", "--quiet", *argv], capture_output=True, text=True,
                           env=env, timeout=HANG_S)
        assert r.returncode == 2 and match in r.stderr, r.stderr
    assert os.listdir(tmp_path) == []
