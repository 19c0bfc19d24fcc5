"""Rough conductor / dielectric (GGX, Beckmann): chi2 of every sampler, consistency, furnace,
reciprocity, the Smith Lambda against quadrature, index-matched and extreme interfaces."""
import numpy as np
import pytest

import bsdflab as bl
from bsdflab import Lobe
from bsdflab.testing import (
    albedo_sampled,
    albedo_uniform,
    bsdf_chi2,
    eval_pdf_consistency,
    random_unit_vectors,
    reciprocity_error,
)
from support.directions import directions_at
from support.microfacet_energy import energy_with_error

SIGNIFICANCE = 0.01
FILM = [{"material": 2.0, "thickness_nm": 400.0}]

# (model, incident cos theta) pairs; negative cos = from below; TIR: from inside glass
# beyond the critical angle most microfacets reflect totally.
CHI2_CASES = [
    (lambda: bl.RoughConductor(0.05, material="Au"), 1.0),
    (lambda: bl.RoughConductor(0.3, material="Cu"), 0.05),
    (lambda: bl.RoughConductor(0.7, eta=1.5, k=2.0), 0.5),
    (lambda: bl.RoughConductor(0.3, material="Ag", two_sided=True), -0.4),
    (lambda: bl.RoughConductor(0.2, material="Al", film=FILM), 0.7),
    (lambda: bl.RoughDielectric(0.1, 1.5, 1.0), 0.8),
    (lambda: bl.RoughDielectric(0.5, 1.5, 1.0), 0.05),
    (lambda: bl.RoughDielectric(0.3, 1.5, 1.0), -0.6),
    (lambda: bl.RoughDielectric(0.3, 1.5, 1.0), -0.3),   # TIR region (critical cos 0.745)
    (lambda: bl.RoughDielectric(0.2, 1.0, 1.33), 0.6),   # interior less dense than exterior
    (lambda: bl.RoughDielectric(0.3, 1.5, 1.0, film=FILM), 0.5),
    (lambda: bl.RoughDielectric(0.3, 1.5, 1.0, film=FILM), -0.5),
    (lambda: bl.RoughConductor(0.5, material="Cu", distribution="beckmann"), 0.05),
    (lambda: bl.RoughDielectric(0.3, 1.5, 1.0, distribution="beckmann"), -0.3),  # TIR
    (lambda: bl.RoughDielectric(0.8, 1.0, 1.33, distribution="beckmann"), -0.8),
    pytest.param(lambda: bl.RoughConductor(0.05, material="Au", distribution="beckmann"), 0.9,
                 marks=pytest.mark.slow),
    pytest.param(lambda: bl.RoughDielectric(0.3, 1.5, 1.0, distribution="beckmann"), 0.7,
                 marks=pytest.mark.slow),
    pytest.param(lambda: bl.RoughDielectric(0.2, 1.5, 1.0, film=FILM, distribution="beckmann"),
                 0.5, marks=pytest.mark.slow),
]


# test_01's CI sample: 10 of the 18 (every dielectric case but the film from below; the
# conductors at alpha 0.05 head-on and two-sided from below). The slow rest: the other
# conductors (~5 CPU-s each: grazing Cu GGX and Beckmann, alpha 0.7, the film on Al), the
# dielectric film from below and the three slow ones above. Each set is its own family.
CHI2_SLOW = {1, 2, 4, 11, 12, 15, 16, 17}
CHI2_CI_CASES = [c if i not in CHI2_SLOW or type(c) is not tuple else pytest.param(*c, marks=pytest.mark.slow)
                 for i, c in enumerate(CHI2_CASES)]
CHI2_CI_COUNT = len(CHI2_CASES) - len(CHI2_SLOW)


@pytest.mark.parametrize("make, cos_theta", CHI2_CI_CASES)
def test_01_chi2(make, cos_theta, request):
    """Mutation: the rough interfaces' pdf x 1.05 for wo.x > 0 fails it."""
    slow = request.node.get_closest_marker("slow") is not None
    # order 16: the alpha = 0.05 lobe is ~0.005 wide in cos(theta), cells are 0.065 wide
    test = bsdf_chi2(make(), directions_at(cos_theta), significance=SIGNIFICANCE,
                     test_count=len(CHI2_SLOW) if slow else CHI2_CI_COUNT, sample_count=300_000, seed=1,
                     quadrature_order=16)
    assert test.run(), test.message


@pytest.mark.parametrize("make, cos_theta", CHI2_CASES)
def test_02_eval_pdf_consistency(make, cos_theta):
    r = eval_pdf_consistency(make(), directions_at(cos_theta), n=20_000, seed=2)
    assert r.max_pdf_error < 1e-8 and r.max_weight_error < 1e-8, r


# The quadrature reference at 256 / 512 nodes per axis (its error: the change between the
# two): <= 5e-6 on the CI cases, below 1/20 of 4.5 standard errors wherever the sampled
# estimate has any noise; 512 / 1024 cost 4 x the CPU (2-4 CPU-s a case), no verdict changes.
QUADRATURE_NODES = 256
FURNACE_CI = {(1.0, 0.05, "ggx"), (0.1, 0.3, "ggx"), (0.5, 0.8, "ggx"),
              (0.5, 0.05, "beckmann"), (1.0, 0.3, "beckmann"), (0.1, 0.8, "beckmann")}


@pytest.mark.parametrize("cos_theta, alpha, dist", [
    pytest.param(c, a, d, marks=() if (c, a, d) in FURNACE_CI else pytest.mark.slow)
    for c in (1.0, 0.5, 0.1) for a in (0.05, 0.3, 0.8) for d in ("ggx", "beckmann")])
def test_03_white_furnace_perfect_mirror_microfacets(dist, alpha, cos_theta):
    """With R = 1 microfacets, the albedo is the single-scattering G1 loss (0.43-1.0 here):
    the importance-sampled albedo equals the quadrature of the visible-normal expectation
    (support/microfacet_energy.py) within 4.5 standard errors plus twice the quadrature's
    own error (at least its 1e-9 round-off), and the uniform-sampling estimate agrees.
    CI runs 6 of the 18 (FURNACE_CI: a Latin square, every distribution at every alpha and
    every angle); the rest are slow. Quadrature at QUADRATURE_NODES.
    Mutation: the sample weight x 1.02 (a wrapper of sample) fails all 6 CI cases."""
    m = bl.RoughConductor(alpha, distribution=dist)  # perfect-mirror facets
    wi = directions_at(cos_theta)
    u = albedo_uniform(m, wi, n=400_000, seed=3, wavelengths=[550.0])
    s = albedo_sampled(m, wi, n=200_000, seed=3, wavelengths=[550.0])
    reference, quadrature_error = energy_with_error(dist, alpha, np.reshape(wi, 3), n=QUADRATURE_NODES)
    assert abs(s.mean[0] - reference) < 4.5 * s.stderr[0] + 2 * max(quadrature_error, 1e-9), (s.mean[0], reference)
    assert abs(u.mean[0] - s.mean[0]) < 4.5 * np.hypot(u.stderr[0], s.stderr[0])


DIELECTRIC_FURNACE_CI = {(0.9, 0.1), (0.3, 0.4), (-0.3, 0.1), (-0.9, 0.4)}


@pytest.mark.parametrize("cos_theta, alpha", [
    pytest.param(c, a, marks=() if (c, a) in DIELECTRIC_FURNACE_CI else pytest.mark.slow)
    for c in (0.9, 0.3, -0.9, -0.3) for a in (0.1, 0.4)])
def test_04_white_furnace_dielectric(alpha, cos_theta):
    """R + T (radiance scaling undone) is the single-scattering energy (< 1: light that
    would bounce between microfacets is lost): it equals the quadrature of the visible-
    normal expectation with exact Fresnel (support/microfacet_energy.py) within 4.5
    standard errors plus twice the quadrature's own error (at least its 1e-9 round-off).
    CI runs 4 of the 8 (each angle once, each alpha from above and below); the rest are
    slow. Quadrature at QUADRATURE_NODES.
    Mutation: the sample weight x 1.02 (a wrapper of sample) fails all 4 CI cases."""
    g = bl.RoughDielectric(alpha, 1.5, 1.0)
    wi = np.tile(directions_at(cos_theta), (200_000, 1))
    s = g.sample(wi, seed=4, wavelengths=[550.0])
    unscaled = np.where(s.lobe == Lobe.GLOSSY_TRANSMISSION, s.weight[:, 0] * s.eta ** 2, s.weight[:, 0])
    mean, err = unscaled.mean(), unscaled.std() / np.sqrt(len(unscaled))
    reference, quadrature_error = energy_with_error("ggx", alpha, wi[0], eta=1.5, n=QUADRATURE_NODES)
    assert abs(mean - reference) < 4.5 * err + 2 * max(quadrature_error, 1e-9), (mean, reference, err)


@pytest.mark.parametrize("make", [lambda: bl.RoughConductor(0.3, material="Au"),
                                  lambda: bl.RoughDielectric(0.3, 1.5, 1.0),
                                  lambda: bl.RoughDielectric(0.3, 1.5, 1.0, film=FILM)])
def test_05_reciprocity_of_reflection(make):
    m = make()
    wi = random_unit_vectors(3000, seed=5, hemisphere="upper")
    wo = random_unit_vectors(3000, seed=6, hemisphere="upper")
    assert np.max(reciprocity_error(m, wi, wo, wavelengths=[450.0, 550.0, 650.0])) < 1e-9


def test_06_generalised_reciprocity_of_transmission():
    """Veach (1997, sec. 5.2): f(w_light -> w_view) / n_view^2 = f(w_view -> w_light) / n_light^2.
    eval(wi, wo) is f(wo -> wi) (wi faces the camera), so with wi outside (n = 1) and wo
    inside glass: eval(wo, wi) = eta^2 eval(wi, wo) for the BSDF values (cosines removed)."""
    eta = 1.5
    g = bl.RoughDielectric(0.3, eta, 1.0)
    wi = random_unit_vectors(3000, seed=7, hemisphere="upper")
    wo = random_unit_vectors(3000, seed=8, hemisphere="lower")
    f_io = g.eval(wi, wo, wavelengths=[550.0])[:, 0] / np.abs(wo[:, 2])
    f_oi = g.eval(wo, wi, wavelengths=[550.0])[:, 0] / np.abs(wi[:, 2])
    assert np.count_nonzero(f_io) > 500  # many random pairs admit no microfacet
    assert np.allclose(f_oi, eta**2 * f_io, rtol=1e-9, atol=1e-300)


def test_07_smooth_limit():
    """As alpha -> 0 the rough conductor's albedo approaches the smooth Fresnel value."""
    wi = directions_at(0.6)
    smooth = bl.Conductor(material="Au").sample(wi, wavelengths=[550.0]).weight[0, 0]
    rough = albedo_sampled(bl.RoughConductor(1e-3, material="Au"), wi, n=20_000, seed=9,
                           wavelengths=[550.0]).mean[0]
    assert rough == pytest.approx(smooth, rel=1e-3)


def test_08_film_thickness_per_query_changes_colour():
    m = bl.RoughDielectric(0.2, 1.5, 1.0, film=FILM)
    wi = np.tile(directions_at(0.8), (3, 1))
    wo = np.tile(directions_at(0.8, 0.3 + np.pi), (3, 1))
    rgb = m.eval(wi, wo, thickness_nm=[0.0, 300.0, 400.0])
    bare = bl.RoughDielectric(0.2, 1.5, 1.0).eval(wi[:1], wo[:1])
    assert np.allclose(rgb[0], bare[0], rtol=1e-12)  # zero thickness = bare interface
    assert np.allclose(rgb[2], m.eval(wi[:1], wo[:1])[0], rtol=1e-12)  # default = 400 nm
    assert not np.allclose(rgb[1], rgb[2], rtol=0.05)
    with pytest.raises(ValueError, match="thickness_nm must be >= 0"):
        m.eval(wi, wo, thickness_nm=-1.0)


@pytest.mark.parametrize("make, match", [
    (lambda: bl.RoughConductor(0.0), "alpha must be >= 0.0001"),
    (lambda: bl.RoughConductor(np.nan), "alpha must be finite"),
    (lambda: bl.RoughDielectric(5.0), "alpha must be <= 4"),
    (lambda: bl.RoughDielectric(0.1, 1.0, 1.0), "int_ior must differ"),
    (lambda: bl.RoughDielectric(0.1, distribution="phong"), "distribution must be one of"),
    (lambda: bl.RoughConductor(0.1, distribution=3), "distribution must be one of"),
    (lambda: bl.RoughDielectric(0.1, film=[{"material": 1.5}]), "film\\[0\\]"),
    (lambda: bl.RoughDielectric(0.1, film=[{"material": 1.5, "thickness_nm": -3}]), "thickness_nm"),
])
def test_09_bad_input(make, match):
    with pytest.raises(ValueError, match=match):
        make()


@pytest.mark.parametrize("dist", ["ggx", "beckmann"])
@pytest.mark.parametrize("alpha", [0.1, 0.5, 1.5])
def test_10_smith_lambda_and_ndf_against_quadrature(dist, alpha):
    """The core's D is normalised (int D cos theta_m = 1) and its Lambda satisfies Smith's
    relation int D(m) max(0, v.m) dm = v.z (1 + Lambda(v)) (Heitz 2014, eq. 5), by a
    400 x 400 Gauss-Legendre product quadrature over the normals' hemisphere (theta_m =
    (pi / 2) s^2 crowds the nodes near the normal) of the oracle's numpy D, which equals
    the core's to 1e-12. Converged to ~1e-6 (800 nodes move it by that); the kink of
    max(0, v.m) near grazing allows 1e-5."""
    from bsdflab import _core
    from bsdflab.oracles.microsurface import ndf
    x, w = np.polynomial.legendre.leggauss(400)
    s = (x + 1) / 2
    theta, dtheta = 0.5 * np.pi * s**2, 0.5 * np.pi * s  # d theta / dx
    phi = np.pi * (x + 1)
    T, P = np.meshgrid(theta, phi, indexing="ij")
    W = np.outer(w * dtheta, w * np.pi).ravel() * np.sin(T).ravel()
    m = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], axis=-1).reshape(-1, 3)
    D = ndf(dist, alpha, m)
    some = np.random.default_rng(10).choice(len(m), 500, replace=False)
    core_d = np.array([_core.microfacet_d(dist, alpha, list(v)) for v in m[some]])
    assert np.allclose(core_d, D[some], rtol=1e-12, atol=0)
    assert np.sum(D * m[:, 2] * W) == pytest.approx(1.0, abs=1e-6)
    for deg in (0.0, 30.0, 60.0, 80.0, 89.0):
        v = np.array([np.sin(np.radians(deg)), 0.0, np.cos(np.radians(deg))])
        lhs = np.sum(D * np.maximum(0.0, m @ v) * W)
        lam = _core.microfacet_lambda(dist, alpha, list(v))
        assert lhs == pytest.approx(v[2] * (1 + lam), rel=1e-5, abs=1e-9), (deg, lhs, lam)


def test_11_near_index_matched_rough_dielectric_is_no_interface():
    """Regression (issue 16): 1.0000000001 vs 1.0 evaluated to 9e19. Within a relative
    1e-6 the interface passes light straight through: eval and pdf are 0 (delta lobes
    only), sampling returns -wi with weight 1 (R ~ 1e-21)."""
    g = bl.RoughDielectric(0.3, 1.0000000001, 1.0)
    wi = random_unit_vectors(500, seed=11)
    wo = random_unit_vectors(500, seed=12)
    assert np.all(g.eval(wi, wo) == 0) and np.all(g.pdf(wi, wo) == 0)
    assert g.lobes & Lobe.DELTA_TRANSMISSION and not g.lobes & Lobe.GLOSSY
    s = g.sample(wi, seed=13, wavelengths=[550.0])
    t = s.lobe == Lobe.DELTA_TRANSMISSION
    assert np.mean(t) > 0.999
    assert np.allclose(s.wo[t], -wi[t], atol=1e-6, rtol=0)  # bent by (eta - 1) tan theta
    assert np.allclose(s.weight[t], 1.0, atol=1e-8, rtol=0)
    # a relative difference of 1e-4 is still a rough interface
    assert bl.RoughDielectric(0.3, 1.0001, 1.0).lobes & Lobe.GLOSSY_TRANSMISSION


@pytest.mark.parametrize("int_ior, ext_ior", [(1e200, 1.0), (1.0, 1e200), (1e-200, 1.0), (1.5, 1e-200)])
@pytest.mark.parametrize("dist", ["ggx", "beckmann"])
def test_12_extreme_indices_give_finite_answers_in_the_core(int_ior, ext_ior, dist):
    """Regression (issue 16): RoughDielectric(0.3, int_ior=1e200) evaluated to NaN (the
    Fresnel term at normal incidence formed inf * 0). The core (called directly: Python
    bounds indices) answers finite values for every direction pair and sample."""
    from bsdflab import _core
    for multiscatter in (False, True):
        r = _core.RoughInterface([550.0], _core.DielectricTerm(1, int_ior, ext_ior), 0.3, False,
                                 dist, multiscatter)
        wi = random_unit_vectors(3000, seed=14)
        wo = random_unit_vectors(3000, seed=15)
        # include the exact normal and mirror configurations
        wi[:2] = [[0, 0, 1], [0, 0, -1]]
        wo[:2] = [[0, 0, -1], [0, 0, 1]]
        assert np.all(np.isfinite(r.eval(wi, wo)))
        assert np.all(np.isfinite(r.pdf(wi, wo)))
        u = np.random.default_rng(16).random((len(wi), 3))
        wo_s, weight, pdf, lobe, eta = r.sample(wi, u[:, 0], u[:, 1:])
        for a in (wo_s, weight, pdf, eta):
            assert np.all(np.isfinite(a))
        assert np.all((lobe == 0) | (pdf > 0))


def test_13_near_matched_threshold_is_the_physical_limit_not_the_models():
    """Review finding (documented in docs/rough_interfaces.md): below the 1e-6 threshold the
    interface is a pass-through (albedo 1, Heitz et al.'s microsurface walk agrees), just
    above it the single-scattering model keeps its own limit G1(wi) = 1/(1 + Lambda(wi)),
    so albedo jumps; with energy compensation the energy is continuous (1 on both sides).
    Tolerance: 4 standard errors of the 20 000-sample mean plus the tables' 2e-3."""
    theta, alpha, n = 1.2, 0.5, 20000
    wi = np.tile([np.sin(theta), 0.0, np.cos(theta)], (n, 1))
    g1 = 2.0 / (1.0 + np.sqrt(1.0 + alpha**2 * np.tan(theta) ** 2))  # GGX: 1 / (1 + Lambda)

    def albedo(d, multiscatter):
        b = bl.RoughDielectric(alpha=alpha, int_ior=1.0 + d, ext_ior=1.0, multiscatter=multiscatter)
        s = b.sample(wi, seed=0, wavelengths=[550.0])
        w = np.where(s.lobe == 0, 0.0, s.weight[:, 0]) * np.where(s.wo[:, 2] < 0, s.eta**2, 1.0)
        return w.mean(), w.std() / np.sqrt(n)

    for multiscatter, above in ((False, g1), (True, 1.0)):
        below_mean, _ = albedo(0.99e-6, multiscatter)
        above_mean, above_se = albedo(1.01e-6, multiscatter)
        assert below_mean == pytest.approx(1.0, abs=1e-12)
        assert abs(above_mean - above) < 4 * above_se + 2e-3, (multiscatter, above_mean, above)
