"""Diffuse: numbered tests in Mitsuba's style (create, values, consistency, chi2, furnace)."""
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

SIGNIFICANCE = 0.01  # family-wise false-alarm rate of the statistical tests in this file


def test_01_create():
    d = bl.Diffuse()
    assert d.lobes == Lobe.DIFFUSE_REFLECTION
    assert d.to_dict() == {"type": "diffuse", "reflectance": {"type": "constant", "value": 0.5},
                           "two_sided": False}


def test_02_analytic_values_per_wavelength():
    refl = {"type": "tabulated", "wavelengths": [400.0, 700.0], "values": [0.2, 0.8]}
    d = bl.Diffuse(refl)
    wi = random_unit_vectors(500, seed=1, hemisphere="upper")
    wo = random_unit_vectors(500, seed=2, hemisphere="upper")
    wl = np.array([400.0, 550.0, 700.0])
    expected = np.array([0.2, 0.5, 0.8])[None, :] / np.pi * wo[:, 2:3]
    assert np.allclose(d.eval(wi, wo, wavelengths=wl), expected, rtol=1e-14, atol=0)
    assert np.allclose(d.pdf(wi, wo), wo[:, 2] / np.pi, rtol=1e-14)


def test_03_rgb_albedo_reproduced_in_colour():
    rgb = np.array([0.8, 0.4, 0.2])
    up = np.array([0.0, 0.0, 1.0])
    # RGB -> spectrum (Mallett-Yuksel) -> RGB round-trips to <= 3e-4 on the 5 nm grid
    assert np.allclose(bl.Diffuse(rgb).eval(up, up)[0] * np.pi, rgb, atol=3e-4, rtol=0)


def test_04_one_sided_underside_is_black_two_sided_mirrors():
    wi, wo = directions_at(-0.6), directions_at(-0.8, 2.0)
    one, two = bl.Diffuse(0.5), bl.Diffuse(0.5, two_sided=True)
    assert np.all(one.eval(wi, wo) == 0) and one.pdf(wi, wo)[0] == 0
    assert one.sample(np.tile(wi, (10, 1))).lobe.max() == 0
    mixed = two.eval(wi, -wo)  # light below, viewer above: a reflector transmits nothing
    assert np.allclose(two.eval(wi, wo), bl.Diffuse(0.5).eval(wi * [1, 1, -1], wo * [1, 1, -1]), rtol=1e-14, atol=0)
    assert mixed.max() == 0
    s = two.sample(np.tile(wi, (1000, 1)), seed=4)
    assert np.all(s.wo[:, 2] < 0) and np.all(s.lobe == Lobe.DIFFUSE_REFLECTION)


@pytest.mark.parametrize("two_sided", [False, True])
def test_05_eval_pdf_consistency(two_sided):
    d = bl.Diffuse([0.3, 0.6, 0.9], two_sided=two_sided)
    for cos in (1.0, 0.4, 0.05) + ((-0.5,) if two_sided else ()):
        r = eval_pdf_consistency(d, directions_at(cos), n=20_000, seed=5)
        assert r.max_weight_error < 1e-12 and r.max_pdf_error < 1e-12


CHI2_CASES = [(1.0, False), (0.05, False), (0.5, False), (-0.5, True), (-0.05, True)]


@pytest.mark.parametrize("cos_theta, two_sided", CHI2_CASES)
def test_06_chi2(cos_theta, two_sided):
    test = bsdf_chi2(bl.Diffuse(0.7, two_sided=two_sided), directions_at(cos_theta),
                     significance=SIGNIFICANCE, test_count=len(CHI2_CASES),
                     sample_count=300_000, seed=6)
    assert test.run(), test.message


@pytest.mark.parametrize("albedo", [1.0, 0.3])
@pytest.mark.parametrize("cos_theta", [1.0, 0.3, 0.05])
def test_07_white_furnace(albedo, cos_theta):
    d = bl.Diffuse(albedo)
    wi = directions_at(cos_theta)
    u = albedo_uniform(d, wi, n=400_000, seed=7, wavelengths=[550.0])
    s = albedo_sampled(d, wi, n=1000, seed=7, wavelengths=[550.0])
    # 4.5 standard errors: two-sided false-alarm probability < 1e-5 per check
    assert abs(u.mean[0] - albedo) < 4.5 * u.stderr[0]
    assert s.mean[0] == pytest.approx(albedo, abs=1e-12)  # weights are exactly the albedo


def test_08_reciprocity():
    d = bl.Diffuse([0.2, 0.5, 0.9])
    wi = random_unit_vectors(2000, seed=8, hemisphere="upper")
    wo = random_unit_vectors(2000, seed=9, hemisphere="upper")
    assert np.max(reciprocity_error(d, wi, wo)) < 1e-12
