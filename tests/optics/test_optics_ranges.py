"""Optics at the ends of their ranges: inputs that would give NaN are refused with a
ValueError naming the parameter; accepted extremes and index-matched or absent films at
grazing incidence stay finite (each failed before its fix: noted beside it)."""
from __future__ import annotations

import numpy as np
import pytest

import bsdflab as bl
from bsdflab import optics

UP = np.array([0.0, 0.0, 1.0])
OBLIQUE = np.array([0.6, 0.0, 0.8])


@pytest.mark.parametrize("call, name", [
    (lambda: optics.film_reflectance((1.0, 4e38, 100.0, 1.5), 550.0, 0.3), "n1"),       # old: NaN
    (lambda: optics.film_reflectance((1e-201, 1.5, 100.0, 1.5), 550.0, 0.3), "n0"),
    (lambda: optics.film_reflectance((1.0, 1.5, 1e308, 1.5), 550.0, 0.3), "d_nm"),
    (lambda: optics.film_reflectance((1.0, 1.5, 100.0, 1.5), 1e-310, 0.3), "wavelength_nm"),
    (lambda: optics.film_transmittance((1.0, 1.5, 100.0, 1.5), 550.0, 0.3, thickness_nm=1e308), "thickness_nm"),
    (lambda: optics.fresnel_reflectance(0.5, 1e-250, 1.5), "n_i"),
    (lambda: bl.Diffuse(0.5).eval(UP, OBLIQUE, wavelengths=[5e-324]), "wavelengths"),
    (lambda: bl.Dielectric(film=[{"material": 1.8, "thickness_nm": 300}]).sample(OBLIQUE, thickness_nm=1e300),
     "thickness"),
])
def test_optics_refuse_what_would_be_nan(call, name):
    with pytest.raises(ValueError, match=name):
        call()


def test_film_at_the_ends_of_the_documented_ranges_is_finite():
    r = optics.film_reflectance((1e-3, 1e3, 1e9, 1e3 + 1e3j), [1.0, 1e12], cos_theta=[0.0, 1.0])
    assert np.all(np.isfinite(r)) and np.all((r >= 0) & (r <= 1))
    # a lossless film at the ends of the ranges conserves energy: R + T = 1 (grazing: R = 1,
    # T = 0). Mutation caught: a clamp or underflow guard that zeroes R or T at the extremes
    # (R + T < 1), or one that returns 1 for both.
    lossless = (1e-3, 1e3, 1e9, 1e3)
    for cos in ([0.0, 1.0], [1e-6, 0.5]):
        R = optics.film_reflectance(lossless, [1.0, 1e12], cos_theta=cos)
        T = optics.film_transmittance(lossless, [1.0, 1e12], cos_theta=cos)
        assert np.allclose(R + T, 1.0, rtol=0, atol=1e-9), (cos, R, T)


def test_index_matched_and_absent_films_at_grazing_are_finite():
    # found by this fuzzing (old: NaN): equal media, or a zero-thickness film
    # between equal media, near grazing incidence divided 0 by 0; either is no interface
    c = np.array([1e-30, 1e-70, 1e-300, 0.5])
    assert np.array_equal(optics.fresnel_reflectance(c, 1.5, 1.5).unpolarised, np.zeros(4))
    assert np.array_equal(optics.fresnel_transmittance(c, 1.5, 1.5).unpolarised, np.ones(4))
    for film in ((1.0, 2.0, 0.0, 1.0), (1.3, 1.3, 100.0, 1.3), (1.3, 1.3, 0.0, 1.3)):
        r = optics.film_reflectance(film, 500.0, cos_theta=c)
        t = optics.film_transmittance(film, 500.0, cos_theta=c)
        np.testing.assert_allclose(r, 0.0, atol=1e-12, rtol=0)
        np.testing.assert_allclose(t, 1.0, atol=1e-12, rtol=0)
