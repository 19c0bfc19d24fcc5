"""Conductor: a Fresnel-weighted mirror; values against `tmm`, sampling, furnace."""
import numpy as np
import pytest
import tmm

import bsdflab as bl
from bsdflab import Lobe
from bsdflab.optics.metals import METALS, metal_ior, metal_provenance
from bsdflab.spectra import spectrum_to_rgb
from bsdflab.testing import discrete_choice_chi2, random_unit_vectors
from support.directions import directions_at

SIGNIFICANCE = 0.01
AIR = 1.000277


def tmm_unpolarised_R(n_metal, theta, n_ext=AIR):
    return np.mean([tmm.coh_tmm(p, [n_ext, n_metal], [np.inf, np.inf], theta, 550.0)["R"]
                    for p in "sp"])


def test_01_create_named_metals_with_provenance():
    for m in METALS:
        c = bl.Conductor(material=m)
        assert c.lobes == Lobe.DELTA_REFLECTION
        assert "Source:" in metal_provenance(m)
        eta, k = metal_ior(m)
        assert np.all(eta.at(bl.DEFAULT_WAVELENGTHS) > 0) and np.all(k.at(bl.DEFAULT_WAVELENGTHS) > 0)
    assert bl.Conductor().to_dict() == {"type": "conductor", "ext_ior": AIR, "two_sided": False}


@pytest.mark.parametrize("metal", METALS)
@pytest.mark.parametrize("theta", [0.0, 0.5, 1.0, 1.4, 1.52])
def test_02_sample_weight_is_fresnel_reflectance(metal, theta):
    wl = np.array([420.0, 550.0, 680.0])
    eta, k = metal_ior(metal)
    wi = directions_at(np.cos(theta), 0.7)
    s = bl.Conductor(material=metal).sample(wi)
    expected = [tmm_unpolarised_R(e + 1j * kk, theta) for e, kk in zip(eta.at(wl), k.at(wl), strict=True)]
    s = bl.Conductor(material=metal).sample(wi, wavelengths=wl)
    assert np.allclose(s.weight[0], expected, rtol=1e-12, atol=1e-14)
    assert np.allclose(s.wo[0], wi * [-1, -1, 1], atol=1e-15, rtol=0)
    assert s.pdf[0] == 1.0 and s.lobe[0] == Lobe.DELTA_REFLECTION


def test_03_eval_and_pdf_are_zero_for_a_delta_lobe():
    c = bl.Conductor(material="Au")
    wi = random_unit_vectors(100, seed=3, hemisphere="upper")
    assert np.all(c.eval(wi, wi * [-1, -1, 1]) == 0) and np.all(c.pdf(wi, wi * [-1, -1, 1]) == 0)


CHOICE_CASES = [1.0, 0.05, -0.5]


@pytest.mark.parametrize("cos_theta", CHOICE_CASES)
def test_04_sampling_always_mirrors(cos_theta):
    """The only outcome is the mirror reflection (one-sided: nothing from below)."""
    wi = directions_at(cos_theta)
    s = bl.Conductor(material="Cu").sample(np.tile(wi, (20_000, 1)), seed=4)
    expected = {int(Lobe.DELTA_REFLECTION): 1.0} if cos_theta > 0 else {0: 1.0}
    r = discrete_choice_chi2(s.lobe, expected, SIGNIFICANCE, test_count=len(CHOICE_CASES))
    assert r.passed, r.message
    if cos_theta > 0:
        assert np.allclose(s.wo, wi * [-1, -1, 1], atol=1e-15, rtol=0)


def test_05_two_sided_reflects_below_with_the_same_reflectance():
    wi = directions_at(-0.6)
    c = bl.Conductor(material="Ag", two_sided=True)
    below, above = c.sample(wi), c.sample(wi * [1, 1, -1])
    assert below.wo[0, 2] < 0 and np.allclose(below.weight, above.weight, rtol=1e-14)


def test_06_furnace_energy_and_colour():
    """A smooth conductor's albedo is its Fresnel reflectance: 1 for the perfect mirror; for
    gold at normal incidence the closed form |(n0 - n) / (n0 + n)|^2 of the tabulated index
    n = eta + i k, per wavelength, and its sRGB projection in RGB mode (yellow)."""
    up = directions_at(1.0)
    assert np.allclose(bl.Conductor().sample(np.tile(up, (10, 1))).weight, 1.0, rtol=0, atol=1e-15)  # perfect mirror
    wl = bl.DEFAULT_WAVELENGTHS
    eta, k = (s.at(wl) for s in metal_ior("Au"))
    gold_model = bl.Conductor(material="Au")
    n0, n = gold_model.ext_ior, eta + 1j * k
    closed = np.abs((n0 - n) / (n0 + n)) ** 2
    spectral = gold_model.sample(up, wavelengths=wl).weight[0]
    np.testing.assert_allclose(spectral, closed, rtol=1e-12, atol=0)
    gold = gold_model.sample(up).weight[0]
    np.testing.assert_allclose(gold, spectrum_to_rgb(closed, wl), rtol=1e-9, atol=0)
    assert gold[0] > gold[1] > gold[2]  # gold is yellow (R > G > B)


def test_07_reciprocity_of_the_mirror():
    c = bl.Conductor(material="Al")
    wi = random_unit_vectors(1000, seed=7, hemisphere="upper")
    there = c.sample(wi)
    back = c.sample(there.wo)
    assert np.allclose(back.wo, wi, atol=1e-15, rtol=0)
    assert np.allclose(back.weight, there.weight, rtol=1e-13)
