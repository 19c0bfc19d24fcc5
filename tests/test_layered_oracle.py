"""PFMC against the deterministic coated-diffuse oracle (tmm + quadrature): smooth top with
and without a thin film, absorbing slab at several optical depths, Lambertian base.

Statistics as in test_layered.py: z = (PFMC - oracle) / stderr over all pairs and
wavelengths; max |z| below the Sidak-corrected two-sided normal quantile at family-wise
significance 0.01, and sum z^2 inside the chi^2 0.5 % / 99.5 % quantiles.
"""
import numpy as np
import pytest

import bsdflab as bl
from bsdflab.oracles import CoatedDiffuseOracle
from bsdflab.testing import random_unit_vectors
from test_layered import assert_agrees

FILMS = {
    "bare": None,
    "guanine 400 nm": [{"material": 1.83, "thickness_nm": 400.0}],
    "absorbing 2-layer": [{"material": {"model": "constant", "n": 2.0, "k": 0.05}, "thickness_nm": 150.0},
                          {"material": 1.33, "thickness_nm": 220.0}],
}
WAVELENGTHS = [450.0, 550.0, 650.0]


@pytest.mark.parametrize("film", list(FILMS))
@pytest.mark.parametrize("sigma_a", [0.0, 0.15, 1.0])
def test_01_pfmc_matches_oracle(film, sigma_a):
    thickness, eta, rho = 2.0, 1.55, 0.7
    n = 32
    wi = random_unit_vectors(n, seed=1, hemisphere="upper")
    wo = random_unit_vectors(n, seed=2, hemisphere="upper")
    pfmc = bl.Layered([bl.Dielectric(eta, 1.0, film=FILMS[film])],
                      [bl.Slab(thickness, sigma_a=sigma_a)], bl.Diffuse(rho))
    value, err = pfmc.eval_with_error(wi, wo, wavelengths=WAVELENGTHS, samples=4000, seed=3)
    oracle = CoatedDiffuseOracle(int_ior=eta, ext_ior=1.0, film=FILMS[film], thickness_um=thickness,
                                 sigma_a=sigma_a, base_reflectance=rho)
    ref = oracle.eval(wi, wo, wavelengths=WAVELENGTHS)
    assert_agrees(value.ravel(), err.ravel(), ref.ravel(), f"{film}, sigma_a {sigma_a}")


def test_02_delta_reflectance_is_exact():
    film = FILMS["guanine 400 nm"]
    wi = random_unit_vectors(20, seed=4, hemisphere="upper")
    pfmc = bl.Layered([bl.Dielectric(1.55, 1.0, film=film)], [bl.Slab(1.0)], bl.Diffuse(0.5))
    oracle = CoatedDiffuseOracle(int_ior=1.55, ext_ior=1.0, film=film, thickness_um=1.0,
                                 base_reflectance=0.5)
    assert np.allclose(pfmc.delta_reflectance(wi, wavelengths=WAVELENGTHS),
                       oracle.specular_reflectance(wi, wavelengths=WAVELENGTHS), rtol=1e-10, atol=1e-14)
