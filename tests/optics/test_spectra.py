"""Spectra -> colour, checked against colour-science's own pipeline."""
import colour
import numpy as np
import pytest

from bsdflab.spectra import DEFAULT_WAVELENGTHS, Spectrum, rgb_to_spectrum, spectrum_to_rgb, srgb_weights
from bsdflab.spectra.colour_weights import rgb_colourspace


def colour_reference_rgb(values, wavelengths):
    """colour.sd_to_XYZ (plain integration) -> XYZ_to_RGB with the illuminant's own white."""
    shape = colour.SpectralShape(wavelengths[0], wavelengths[-1], wavelengths[1] - wavelengths[0])
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(shape)
    illum = colour.SDS_ILLUMINANTS["D65"].copy().align(shape)
    sd = colour.SpectralDistribution(dict(zip(wavelengths, values, strict=True)))
    XYZ = colour.sd_to_XYZ(sd, cmfs, illum, method="Integration") / 100
    white = colour.sd_to_XYZ(colour.SpectralDistribution(dict(zip(wavelengths, np.ones_like(values), strict=True))),
                             cmfs, illum, method="Integration") / 100
    return colour.XYZ_to_RGB(XYZ, rgb_colourspace(), illuminant=colour.XYZ_to_xy(white),
                             chromatic_adaptation_transform="Bradford")


def test_01_white_reflector_is_exactly_white():
    W = srgb_weights(DEFAULT_WAVELENGTHS)
    assert np.allclose(W.sum(axis=1), 1.0, atol=1e-12, rtol=0)


@pytest.mark.parametrize("name", ["ramp", "gauss", "oscillating"])
def test_02_matches_colour_science(name):
    wl = DEFAULT_WAVELENGTHS
    v = {"ramp": (wl - 380) / 400,
         "gauss": np.exp(-0.5 * ((wl - 520) / 30) ** 2),
         "oscillating": 0.5 + 0.5 * np.cos(2 * np.pi * wl / 37.0)}[name]
    ours = spectrum_to_rgb(v, wl)
    ref = colour_reference_rgb(v, wl)
    assert np.max(np.abs(ours - ref)) < 1e-6


def test_03_rgb_round_trip_through_spectra():
    # Mallett-Yuksel's basis is linear: grey is exact; colours round-trip to ~1e-4 on 5 nm.
    rgb = np.array([[0.5, 0.5, 0.5], [0.8, 0.4, 0.2], [0.1, 0.9, 0.3]])
    back = spectrum_to_rgb(rgb_to_spectrum(rgb, DEFAULT_WAVELENGTHS), DEFAULT_WAVELENGTHS)
    assert np.allclose(back[0], 0.5, atol=1e-12, rtol=0)
    assert np.max(np.abs(back - rgb)) < 3e-4


def test_04_spectrum_kinds_and_dicts():
    t = Spectrum.tabulated([400, 500, 600], [0.1, 0.5, 0.3])
    assert np.allclose(t.at([400, 450, 700]), [0.1, 0.3, 0.3], rtol=1e-14, atol=0)
    for s in (Spectrum.constant(0.2), Spectrum.rgb([0.1, 0.2, 0.3]), t):
        assert Spectrum.from_dict(s.to_dict()) == s


@pytest.mark.parametrize("call, match", [
    (lambda: Spectrum.tabulated([500, 400], [0.1, 0.2]), "increasing"),
    (lambda: Spectrum.tabulated([400, 500], [0.1]), "equal length"),
    (lambda: Spectrum.from_dict({"type": "blackbody"}), "unknown spectrum type"),
    (lambda: Spectrum.coerce([0.1, 0.2], "reflectance"), "reflectance"),
    (lambda: srgb_weights([-5.0, 400.0]), "wavelengths"),
])
def test_05_bad_input(call, match):
    with pytest.raises(ValueError, match=match):
        call()
