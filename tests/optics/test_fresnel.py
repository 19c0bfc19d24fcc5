"""Fresnel coefficients against closed forms and the independent `tmm` package."""
import numpy as np
import pytest
import tmm

from bsdflab.optics import fresnel_amplitudes, fresnel_reflectance, fresnel_transmittance


def tmm_interface(pol, n_i, n_t, theta, wavelength=550.0):
    return tmm.coh_tmm(pol, [n_i, n_t], [np.inf, np.inf], theta, wavelength)


@pytest.mark.parametrize("n_t", [1.5, 2.419, 0.2 + 3.1j, 1.4 + 0.8j, 0.05 + 4.0j])
@pytest.mark.parametrize("theta", [0.0, 0.3, 0.9, 1.3, 1.55])
def test_01_matches_tmm_amplitudes_and_powers(n_t, theta):
    a = fresnel_amplitudes(np.cos(theta), 1.0, n_t)
    r = fresnel_reflectance(np.cos(theta), 1.0, n_t)
    for pol, amp_r, amp_t, R in (("s", a.r_s, a.t_s, r.s), ("p", a.r_p, a.t_p, r.p)):
        ref = tmm_interface(pol, 1.0, n_t, theta)
        assert abs(amp_r - ref["r"]) < 1e-12
        assert abs(amp_t - ref["t"]) < 1e-12
        assert abs(R - ref["R"]) < 1e-12


@pytest.mark.parametrize("theta", [0.0, 0.2, 0.5, 0.7297, 0.8, 1.2])
def test_02_from_dense_side_incl_total_internal_reflection(theta):
    n_i, n_t = 1.5, 1.0  # critical angle asin(1/1.5) = 0.7297
    r = fresnel_reflectance(np.cos(theta), n_i, n_t)
    for pol, R in (("s", r.s), ("p", r.p)):
        assert abs(R - tmm_interface(pol, n_i, n_t, theta)["R"]) < 1e-10
    if theta > 0.73:
        assert np.allclose([r.s, r.p], 1.0, atol=1e-12, rtol=0)


def test_03_closed_forms():
    n = 1.5
    r = fresnel_reflectance(1.0, 1.0, n)
    assert r.unpolarised == pytest.approx(((n - 1) / (n + 1)) ** 2, abs=1e-15)
    brewster = np.arctan(n)
    assert abs(fresnel_amplitudes(np.cos(brewster), 1.0, n).r_p) < 1e-14
    # averaging the amplitudes (r_s + r_p)/2 is not an energy; energy needs the squared magnitudes
    a = fresnel_amplitudes(np.cos(1.0), 1.0, n)
    assert fresnel_reflectance(np.cos(1.0), 1.0, n).unpolarised == pytest.approx(
        (abs(a.r_s) ** 2 + abs(a.r_p) ** 2) / 2)
    assert abs(((a.r_s + a.r_p) / 2) ** 2 - (abs(a.r_s) ** 2 + abs(a.r_p) ** 2) / 2) > 1e-3


def test_04_energy_conservation_lossless():
    cos_i = np.linspace(0, 1, 101)
    for n_i, n_t in ((1.0, 1.5), (1.5, 1.0), (1.33, 2.4)):
        r = fresnel_reflectance(cos_i, n_i, n_t)
        t = fresnel_transmittance(cos_i[1:], n_i, n_t)
        assert np.allclose(r.s[1:] + t.s, 1, atol=1e-12, rtol=0)
        assert np.allclose(r.p[1:] + t.p, 1, atol=1e-12, rtol=0)


def test_05_broadcasting_and_shapes():
    """A (5, 1) cosine column against a (3,) index row gives the (5, 3) table whose every
    entry is the textbook s / p reflectance of that cosine and index (Born & Wolf, written
    out here). Mutations caught: indices taken along the cosine axis (a transposed or
    reversed broadcast), R_s and R_p swapped, the unpolarised mean weighted wrongly."""
    cos_i = np.linspace(0.1, 1, 5)[:, None]
    n = np.array([1.3, 1.5, 2.0])
    r = fresnel_reflectance(cos_i, 1.0, n)
    cos_t = np.sqrt(1 - (1 - cos_i**2) / n**2)
    R_s = ((cos_i - n * cos_t) / (cos_i + n * cos_t)) ** 2
    R_p = ((n * cos_i - cos_t) / (n * cos_i + cos_t)) ** 2
    assert r.unpolarised.shape == r.s.shape == r.p.shape == (5, 3)
    assert np.allclose(r.s, R_s, rtol=0, atol=1e-14) and np.allclose(r.p, R_p, rtol=0, atol=1e-14)
    assert np.allclose(r.unpolarised, (R_s + R_p) / 2, rtol=0, atol=1e-14)


@pytest.mark.parametrize("kwargs, match", [
    (dict(cos_i=1.2, n_i=1, n_t=1.5), "cos_i"),
    (dict(cos_i=0.5, n_i=-1, n_t=1.5), "n_i"),
    (dict(cos_i=0.5, n_i=1, n_t=1.5 - 0.1j), "k"),
    (dict(cos_i=np.nan, n_i=1, n_t=1.5), "cos_i"),
    (dict(cos_i=[0.5, 0.6], n_i=1, n_t=[1.5, 1.6, 1.7]), "broadcast"),
])
def test_06_bad_input(kwargs, match):
    with pytest.raises(ValueError, match=match):
        fresnel_reflectance(**kwargs)
