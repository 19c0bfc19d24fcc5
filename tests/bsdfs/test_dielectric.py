"""Dielectric: Fresnel vs `tmm`, Snell's law, TIR, lobe choice frequency, energy, reciprocity."""
import numpy as np
import pytest
import tmm

import bsdflab as bl
from bsdflab import Lobe
from bsdflab.testing import discrete_choice_chi2, random_unit_vectors
from support.directions import directions_at

SIGNIFICANCE = 0.01


def tmm_R(n_i, n_t, theta):
    return np.mean([tmm.coh_tmm(p, [n_i, n_t], [np.inf, np.inf], theta, 550.0)["R"] for p in "sp"])


def test_01_create():
    g = bl.Dielectric()
    assert g.lobes == Lobe.DELTA_REFLECTION | Lobe.DELTA_TRANSMISSION
    assert g.to_dict() == {"type": "dielectric", "int_ior": 1.5046, "ext_ior": 1.000277}


@pytest.mark.parametrize("int_ior, ext_ior", [(1.5, 1.0), (2.419, 1.0), (1.0, 1.33), (1.33, 1.5)])
@pytest.mark.parametrize("cos_theta", [1.0, 0.7, 0.3, 0.05, -0.95, -0.6, -0.2])
def test_02_fresnel_and_snell(int_ior, ext_ior, cos_theta):
    g = bl.Dielectric(int_ior, ext_ior)
    wi = directions_at(cos_theta, 1.1)
    n_i, n_t = (ext_ior, int_ior) if cos_theta > 0 else (int_ior, ext_ior)
    theta = np.arccos(abs(cos_theta))
    R = tmm_R(n_i, n_t, theta)
    r = g.sample(wi, u1=[0.0], u2=[[0.5, 0.5]], lobes=Lobe.REFLECTION, wavelengths=[550.0])
    assert r.weight[0, 0] == pytest.approx(R, abs=1e-13)
    assert np.allclose(r.wo[0], wi * [-1, -1, 1], atol=1e-15, rtol=0)
    t = g.sample(wi, u1=[0.0], u2=[[0.5, 0.5]], lobes=Lobe.TRANSMISSION, wavelengths=[550.0])
    if R > 1 - 1e-15:  # total internal reflection: nothing to transmit
        assert t.lobe[0] == 0
        return
    wo = t.wo[0]
    assert np.sign(wo[2]) == -np.sign(wi[2]) and np.linalg.norm(wo) == pytest.approx(1, abs=1e-14)
    assert n_i * np.hypot(wi[0], wi[1]) == pytest.approx(n_t * np.hypot(wo[0], wo[1]), abs=1e-13)
    assert np.allclose(np.cross(wi, [0, 0, 1]) @ wo, 0, atol=1e-14, rtol=0)  # plane of incidence
    if abs(cos_theta) < 1:
        assert np.allclose(wo[:2] / np.hypot(*wo[:2]), -wi[:2] / np.hypot(*wi[:2]), atol=1e-12, rtol=0)
    # weight = T times the radiance scaling (n_i / n_t)^2
    assert t.weight[0, 0] == pytest.approx((1 - R) * (n_i / n_t) ** 2, rel=1e-12)
    assert t.eta[0] == pytest.approx(n_t / n_i, rel=1e-14)


CHOICE_CASES = [(1.0, 1.5), (0.05, 1.5), (-0.7, 1.5), (-0.5, 1.5), (0.4, 0.8)]


@pytest.mark.parametrize("cos_theta, eta", CHOICE_CASES)
def test_03_lobe_choice_frequency(cos_theta, eta):
    """Sampling picks reflection with probability R (chi2 / exact binomial), TIR included:
    from inside glass (eta 1.5) at cos 0.5 (60 deg > critical 41.8 deg) R = 1."""
    g = bl.Dielectric(eta, 1.0)
    wi = directions_at(cos_theta)
    n_i, n_t = (1.0, eta) if cos_theta > 0 else (eta, 1.0)
    R = tmm_R(n_i, n_t, np.arccos(abs(cos_theta)))
    s = g.sample(np.tile(wi, (200_000, 1)), seed=3)
    expected = {int(Lobe.DELTA_REFLECTION): R, int(Lobe.DELTA_TRANSMISSION): 1 - R}
    expected = {k: v for k, v in expected.items() if v > 1e-15}
    r = discrete_choice_chi2(s.lobe, expected, SIGNIFICANCE, test_count=len(CHOICE_CASES))
    assert r.passed, r.message
    # both lobes enabled: reflection weight 1, transmission weight (n_i/n_t)^2
    refl = s.lobe == Lobe.DELTA_REFLECTION
    assert np.allclose(s.weight[refl], 1.0, rtol=1e-14, atol=0)
    assert np.allclose(s.weight[~refl], (n_i / n_t) ** 2, rtol=1e-14, atol=0)


@pytest.mark.parametrize("cos_theta", [1.0, 0.5, 0.05, -0.9, -0.5])
def test_04_energy_conservation(cos_theta):
    """E[weight] with the radiance scaling undone is exactly 1: a lossless interface."""
    g = bl.Dielectric(1.5, 1.0)
    wi = directions_at(cos_theta)
    s = g.sample(np.tile(wi, (100_000, 1)), seed=4, wavelengths=[550.0])
    unscaled = np.where(s.lobe == Lobe.DELTA_TRANSMISSION, s.weight[:, 0] * s.eta ** 2, s.weight[:, 0])
    assert np.allclose(unscaled, 1.0, rtol=1e-12)
    only_r = g.sample(wi, lobes=Lobe.REFLECTION, wavelengths=[550.0]).weight[0, 0]
    only_t = g.sample(wi, lobes=Lobe.TRANSMISSION, wavelengths=[550.0])
    t = only_t.weight[0, 0] * only_t.eta[0] ** 2 if only_t.lobe[0] else 0.0
    assert only_r + t == pytest.approx(1.0, abs=1e-14)


def test_05_generalised_reciprocity():
    """f(wi->wo) / n_o^2 = f(wo->wi) / n_i^2: going back along a refracted ray recovers wi,
    and the two transmitted weights differ exactly by the (n_i/n_t)^2 radiance factors."""
    g = bl.Dielectric(1.5, 1.0)
    wi = random_unit_vectors(2000, seed=5, hemisphere="upper")
    t = g.sample(wi, lobes=Lobe.TRANSMISSION, wavelengths=[550.0])
    back = g.sample(t.wo, lobes=Lobe.TRANSMISSION, wavelengths=[550.0])
    assert np.all(back.lobe == Lobe.DELTA_TRANSMISSION)
    # cos = sqrt(1 - sin^2) loses digits near grazing (z ~ 1e-6 -> 5e-11 absolute)
    assert np.allclose(back.wo, wi, atol=1e-9, rtol=0)
    # Stokes: the same T both ways; the weights carry inverse radiance factors
    assert np.allclose(t.weight[:, 0] * t.eta ** 2, back.weight[:, 0] * back.eta ** 2, rtol=1e-12)


def test_06_grazing_and_degenerate_inputs_stay_finite():
    g = bl.Dielectric(1.5, 1.0)
    wi = np.array([[1.0, 0.0, 1e-12], [1.0, 0.0, -1e-12]])
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    s = g.sample(np.repeat(wi, 1000, axis=0), seed=6)
    assert np.all(np.isfinite(s.weight)) and np.all(np.isfinite(s.wo))
    # Grazing from outside, R -> 1; grazing from inside, beyond the critical angle (TIR):
    # every sample is the mirror reflection with weight 1. Mutations caught: a degenerate
    # direction answered with a failed sample (lobe 0, weight 0) instead of its limit, or
    # a transmission chosen where none exists.
    assert np.all(s.lobe == int(bl.Lobe.DELTA_REFLECTION))
    assert np.allclose(s.weight, 1.0, rtol=0, atol=1e-9)
    mirror = np.repeat(wi * [-1.0, -1.0, 1.0], 1000, axis=0)
    assert np.allclose(s.wo, mirror, rtol=0, atol=1e-12)
