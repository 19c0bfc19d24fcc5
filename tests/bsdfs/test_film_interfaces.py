"""Smooth dielectric and conductor with a thin-film coating: per-wavelength weights against
`tmm`, the lobe choice by the channel-mean reflectance, and energy."""
import numpy as np
import pytest
import tmm

import bsdflab as bl
from bsdflab import Lobe
from bsdflab.testing import discrete_choice_chi2
from support.directions import directions_at

SIGNIFICANCE = 0.01
FILM = [{"material": 1.83, "thickness_nm": 400.0}]
WL = np.array([450.0, 550.0, 650.0])


def tmm_R(n_list, d_list, theta, wl):
    return np.mean([tmm.coh_tmm(p, n_list, d_list, theta, wl)["R"] for p in "sp"])


@pytest.mark.parametrize("cos_theta", [1.0, 0.6, 0.1, -0.8, -0.3])
def test_01_dielectric_film_weights_and_choice(cos_theta):
    g = bl.Dielectric(1.55, 1.0, film=FILM)
    wi = directions_at(cos_theta)
    theta = np.arccos(abs(cos_theta))
    if cos_theta > 0:
        R = np.array([tmm_R([1.0, 1.83, 1.55], [np.inf, 400.0, np.inf], theta, w) for w in WL])
    else:  # from inside: the reversed stack
        R = np.array([tmm_R([1.55, 1.83, 1.0], [np.inf, 400.0, np.inf], theta, w) for w in WL])
    r = g.sample(wi, lobes=Lobe.REFLECTION, wavelengths=WL)
    assert np.allclose(r.weight[0], R, rtol=1e-10)
    s = g.sample(np.tile(wi, (100_000, 1)), seed=1, wavelengths=WL)
    p_r = min(R.mean(), 1.0)  # TIR: R = 1 up to rounding
    expected = {int(Lobe.DELTA_REFLECTION): p_r, int(Lobe.DELTA_TRANSMISSION): 1 - p_r}
    res = discrete_choice_chi2(s.lobe, {k: v for k, v in expected.items() if v > 1e-15},
                               SIGNIFICANCE, test_count=5)
    assert res.passed, res.message
    refl = s.lobe == Lobe.DELTA_REFLECTION
    assert np.allclose(s.weight[refl], R / p_r, rtol=1e-10)
    # lossless film: R + T = 1 per wavelength once the radiance scaling is undone
    t = g.sample(wi, lobes=Lobe.TRANSMISSION, wavelengths=WL)
    if t.lobe[0]:
        assert np.allclose(R + t.weight[0] * t.eta[0] ** 2, 1.0, atol=1e-12, rtol=0)


@pytest.mark.parametrize("theta", [0.0, 0.7, 1.4])
def test_02_conductor_film_matches_tmm(theta):
    c = bl.Conductor(material="Au", film=[{"material": 1.5, "thickness_nm": 250.0}])
    eta, k = bl.optics.metal_ior("Au")
    n_au = eta.at(WL) + 1j * k.at(WL)
    R = np.array([tmm_R([1.000277, 1.5, n], [np.inf, 250.0, np.inf], theta, w) for n, w in zip(n_au, WL, strict=True)])
    s = c.sample(directions_at(np.cos(theta)), wavelengths=WL)
    assert np.allclose(s.weight[0], R, rtol=1e-10)


def test_03_zero_film_thickness_is_the_bare_interface():
    wi = directions_at(0.7)
    coated = bl.Conductor(material="Cu", film=FILM).sample(wi, wavelengths=WL, thickness_nm=0.0)
    bare = bl.Conductor(material="Cu").sample(wi, wavelengths=WL)
    assert np.allclose(coated.weight, bare.weight, rtol=1e-12)
