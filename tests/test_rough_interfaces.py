"""Rough conductor / dielectric (GGX): chi2 of every sampler, consistency, furnace, reciprocity."""
import numpy as np
import pytest

import bsdflab as bl
from bsdflab import Lobe
from bsdflab.testing import (albedo_sampled, albedo_uniform, bsdf_chi2, eval_pdf_consistency,
                             random_unit_vectors, reciprocity_error)
from conftest import directions_at

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
]


@pytest.mark.parametrize("make, cos_theta", CHI2_CASES)
def test_01_chi2(make, cos_theta):
    # order 16: the alpha = 0.05 lobe is ~0.005 wide in cos(theta), cells are 0.065 wide
    test = bsdf_chi2(make(), directions_at(cos_theta), significance=SIGNIFICANCE,
                     test_count=len(CHI2_CASES), sample_count=300_000, seed=1,
                     quadrature_order=16)
    assert test.run(), test.message


@pytest.mark.parametrize("make, cos_theta", CHI2_CASES)
def test_02_eval_pdf_consistency(make, cos_theta):
    r = eval_pdf_consistency(make(), directions_at(cos_theta), n=20_000, seed=2)
    assert r.max_pdf_error < 1e-8 and r.max_weight_error < 1e-8, r


@pytest.mark.parametrize("alpha", [0.05, 0.3, 0.8])
@pytest.mark.parametrize("cos_theta", [1.0, 0.5, 0.1])
def test_03_white_furnace_perfect_mirror_microfacets(alpha, cos_theta):
    """With R = 1 microfacets, the albedo is the single-scattering G1 loss: <= 1, near 1
    for smooth surfaces; the uniform-sampling and importance-sampling estimates agree."""
    m = bl.RoughConductor(alpha)  # perfect-mirror facets
    wi = directions_at(cos_theta)
    u = albedo_uniform(m, wi, n=400_000, seed=3, wavelengths=[550.0])
    s = albedo_sampled(m, wi, n=200_000, seed=3, wavelengths=[550.0])
    assert s.mean[0] <= 1 + 4 * s.stderr[0]
    assert abs(u.mean[0] - s.mean[0]) < 4.5 * np.hypot(u.stderr[0], s.stderr[0])
    if alpha <= 0.05 and cos_theta > 0.3:
        assert s.mean[0] > 0.99


@pytest.mark.parametrize("alpha", [0.1, 0.4])
@pytest.mark.parametrize("cos_theta", [0.9, 0.3, -0.9, -0.3])
def test_04_white_furnace_dielectric(alpha, cos_theta):
    """R + T (radiance scaling undone) is <= 1 and close to 1 for low roughness."""
    g = bl.RoughDielectric(alpha, 1.5, 1.0)
    wi = np.tile(directions_at(cos_theta), (200_000, 1))
    s = g.sample(wi, seed=4, wavelengths=[550.0])
    unscaled = np.where(s.lobe == Lobe.GLOSSY_TRANSMISSION, s.weight[:, 0] * s.eta ** 2, s.weight[:, 0])
    mean, err = unscaled.mean(), unscaled.std() / np.sqrt(len(unscaled))
    assert mean <= 1 + 4 * err
    if alpha == 0.1 and abs(cos_theta) > 0.5:  # grazing: larger single-scattering loss
        assert mean > 0.95


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
    rgb = m.eval(wi, wo, thickness=[0.0, 300.0, 400.0])
    bare = bl.RoughDielectric(0.2, 1.5, 1.0).eval(wi[:1], wo[:1])
    assert np.allclose(rgb[0], bare[0], rtol=1e-12)  # zero thickness = bare interface
    assert np.allclose(rgb[2], m.eval(wi[:1], wo[:1])[0], rtol=1e-12)  # default = 400 nm
    assert not np.allclose(rgb[1], rgb[2], rtol=0.05)
    with pytest.raises(ValueError, match="thickness must be >= 0"):
        m.eval(wi, wo, thickness=-1.0)


@pytest.mark.parametrize("make, match", [
    (lambda: bl.RoughConductor(0.0), "alpha must be >= 0.0001"),
    (lambda: bl.RoughConductor(np.nan), "alpha must be finite"),
    (lambda: bl.RoughDielectric(5.0), "alpha must be <= 4"),
    (lambda: bl.RoughDielectric(0.1, 1.0, 1.0), "int_ior must differ"),
    (lambda: bl.RoughDielectric(0.1, film=[{"material": 1.5}]), "film\\[0\\]"),
    (lambda: bl.RoughDielectric(0.1, film=[{"material": 1.5, "thickness_nm": -3}]), "thickness_nm"),
])
def test_09_bad_input(make, match):
    with pytest.raises(ValueError, match=match):
        make()
