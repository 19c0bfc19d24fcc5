"""The microsurface random-walk oracle (bsdflab.oracles.microsurface; Heitz et al. 2016):
its single-scattering order against the closed-form height-correlated BSDF, energy
conservation, and the reciprocity of its multiple scattering."""
import numpy as np
import pytest
from scipy import stats

from bsdflab.oracles import microsurface as ms

SIGNIFICANCE = 0.01
ALPHA = 0.8  # rough enough that height correlation (1 + L_i + L_o vs (1 + L_i)(1 + L_o)) shows


def _direction(deg, side=1):
    t = np.radians(deg)
    return np.array([np.sin(t), 0.0, side * np.cos(t)])


def _bin_probabilities(wi, alpha, dist, eta, mu_edges, phi_edges, side, nodes=12):
    """Integral of the closed-form order-1 BSDF x cos over each (mu, |phi|) bin of the
    exit hemisphere `side`, by Gauss-Legendre nodes x nodes per bin (x2: phi and -phi)."""
    x, w = np.polynomial.legendre.leggauss(nodes)
    out = np.zeros((len(mu_edges) - 1, len(phi_edges) - 1))
    for i in range(len(mu_edges) - 1):
        a, b = mu_edges[i], mu_edges[i + 1]
        mu = 0.5 * (b - a) * x + 0.5 * (a + b)
        for j in range(len(phi_edges) - 1):
            c, d = phi_edges[j], phi_edges[j + 1]
            phi = 0.5 * (d - c) * x + 0.5 * (c + d)
            M, P = np.meshgrid(mu, phi, indexing="ij")
            s = np.sqrt(1 - M**2)
            wo = np.stack([s * np.cos(P), s * np.sin(P), side * M], axis=-1).reshape(-1, 3)
            f = ms.single_scattering(np.tile(wi, (len(wo), 1)), wo, alpha, dist, eta=eta)
            W = np.outer(w, w).ravel() * 0.25 * (b - a) * (d - c)
            out[i, j] = 2.0 * np.sum(f * W)
    return out


@pytest.mark.parametrize("dist, deg, side, eta", [
    ("ggx", 30, 1, 1.5), ("ggx", 30, -1, 1.5), ("ggx", 60, 1, None),
    ("beckmann", 45, 1, 1.5), ("beckmann", 20, -1, 1.5), ("beckmann", 70, 1, None),
])
def test_01_order_one_is_the_height_correlated_single_scattering_bsdf(dist, deg, side, eta):
    """Walks that leave after one bounce, histogrammed over exit (mu, |phi|) bins on both
    sides, against the closed form integrated over the bins: Pearson chi2 on the
    multinomial counts (cells with expected count < 5 pooled), at 1 % significance; and
    the order-1 energy against the closed form's integral (the remainder cell). Power:
    with the separable G1 G1 instead of the height-correlated G2 the grazing conductor
    case fails (chi2 349 on 68 dof)."""
    alpha, n = ALPHA, 200_000
    wi = _direction(deg, side)
    walks = ms.random_walk(wi, n, alpha, dist, eta=eta, seed=11)
    one = walks.order == 1
    mu_edges, phi_edges = np.linspace(0, 1, 11), np.linspace(0, np.pi, 9)
    observed, expected = [], []
    for exit_side in ((1, -1) if eta else (1,)):
        sel = one & (walks.side == exit_side)
        wo = walks.wo[sel]
        h, _, _ = np.histogram2d(np.abs(wo[:, 2]), np.abs(np.arctan2(wo[:, 1], wo[:, 0])),
                                 bins=[mu_edges, phi_edges])
        observed.append(h.ravel())
        expected.append(n * _bin_probabilities(wi, alpha, dist, eta, mu_edges, phi_edges,
                                               exit_side).ravel())
    observed, expected = np.concatenate(observed), np.concatenate(expected)
    # The rest (higher orders) is one more multinomial cell.
    observed = np.append(observed, n - observed.sum())
    expected = np.append(expected, n - expected.sum())
    low = expected < 5
    o = np.append(observed[~low], observed[low].sum())
    e = np.append(expected[~low], expected[low].sum())
    keep = e > 0
    chi2 = np.sum((o[keep] - e[keep]) ** 2 / e[keep])
    dof = keep.sum() - 1
    p = stats.chi2.sf(chi2, dof)
    assert p > SIGNIFICANCE, f"chi2 {chi2:.1f} on {dof} dof, p = {p:.2e}"


@pytest.mark.parametrize("dist", ["ggx", "beckmann"])
def test_02_lossless_walks_all_leave_and_a_white_conductor_keeps_all_energy(dist):
    """Every walk of a lossless microsurface leaves (none stays past max_order), so R + T
    = 1 from both sides exactly; with F = 1 facets a conductor's albedo is 1."""
    for side in (1, -1):
        w = ms.random_walk(_direction(60, side), 50_000, 0.8, dist, eta=1.5, seed=3)
        assert np.all(w.side != 0) and np.all(w.energy == 1.0)
        assert np.all(w.wo[:, 2] * w.side > 0)
        assert np.allclose(np.linalg.norm(w.wo, axis=1), 1.0, atol=1e-12, rtol=0)
    c = ms.random_walk(_direction(75), 50_000, 1.0, dist, seed=4)
    assert np.all(c.side == 1) and np.all(c.energy == 1.0) and c.order.max() >= 3


def _cosine_directions(n, side, seed):
    rng = np.random.default_rng(seed)
    u1, u2 = rng.random(n), rng.random(n)
    r, phi = np.sqrt(u1), 2 * np.pi * u2
    return np.stack([r * np.cos(phi), r * np.sin(phi), side * np.sqrt(1 - u1)], axis=1)


@pytest.mark.parametrize("dist", ["ggx", "beckmann"])
def test_03_hemispherical_reciprocity_of_transmission(dist):
    """For cosine-weighted incidence, the energy a reciprocal interface transmits from
    outside equals eta^2 times that from inside (flux units; Veach's generalised
    reciprocity integrated over both hemispheres). A z-test at 4.4 sigma (two-sided 1e-5)
    on the two independent means; it fails when the walk mishandles the inside."""
    eta, alpha, n = 1.5, 0.5, 200_000
    t_out = ms.random_walk(_cosine_directions(n, 1, 5), n, alpha, dist, eta=eta, seed=6)
    t_in = ms.random_walk(_cosine_directions(n, -1, 7), n, alpha, dist, eta=eta, seed=8)
    a, sa = t_out.moments(t_out.side == -1)
    b, sb = t_in.moments(t_in.side == 1)
    z = (a[0] - eta**2 * b[0]) / np.hypot(sa[0], eta**2 * sb[0])
    assert abs(z) < 4.4, (a, b, z)
    # Multiple scattering matters here: higher orders carry > 2 % of the energy.
    assert np.mean(t_in.order > 1) > 0.02


def test_04_visible_normals_from_below_the_horizon():
    """The VNDF sampler for directions below the horizon (walks hitting the surface
    while travelling upwards): the normals' mean of max(0, v.m) / (v.m) weighting is
    the projected area; checked by E[1 / (v.m)] = integral of D(m) dm over the
    visible set / projected area, against a quadrature of D."""
    for dist in ("ggx", "beckmann"):
        v = _direction(120)  # 30 deg below the horizon
        m = ms.sample_visible_normals(dist, 0.5, np.tile(v, (400_000, 1)),
                                      np.random.default_rng(9).random((400_000, 2)))
        cos = m @ v
        assert np.all(cos > -1e-12) and np.all(m[:, 2] >= 0)
        est = np.mean(m[:, 2] / cos)  # E[m.z / v.m] = int D m.z dm / int D max(0, v.m) dm
        # quadrature over the upper hemisphere of m
        x, w = np.polynomial.legendre.leggauss(400)
        mu = 0.5 * (x + 1)
        phi = np.pi * (x + 1)
        M, P = np.meshgrid(mu, phi, indexing="ij")
        s = np.sqrt(1 - M**2)
        mm = np.stack([s * np.cos(P), s * np.sin(P), M], axis=-1).reshape(-1, 3)
        W = np.outer(w, w).ravel() * 0.5 * np.pi
        D = ms.ndf(dist, 0.5, mm)
        proj = np.sum(D * np.maximum(0, mm @ v) * W)
        assert np.sum(D * mm[:, 2] * W) == pytest.approx(1.0, abs=2e-3)
        vis = np.maximum(0, mm @ v) > 0
        expected = np.sum(D * mm[:, 2] * vis * W) / proj
        err = np.std(m[:, 2] / cos) / np.sqrt(len(m))
        assert abs(est - expected) < 5 * err + 2e-3 * expected, (dist, est, expected)


def test_05_bad_arguments():
    with pytest.raises(ValueError, match="distribution"):
        ms.random_walk([0, 0, 1], 10, 0.3, "phong")
    with pytest.raises(ValueError, match="alpha"):
        ms.random_walk([0, 0, 1], 10, 0.0)
    with pytest.raises(ValueError, match="from above"):
        ms.random_walk([0, 0, -1], 10, 0.3)
    with pytest.raises(ValueError, match="eta"):
        ms.random_walk([0, 0, 1], 10, 0.3, eta=1.0)
