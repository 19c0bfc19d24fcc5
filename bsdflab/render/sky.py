"""The ``sun`` preset's sky and sun: Preetham, Shirley and Smits (1999), "A Practical
Analytic Model for Daylight", SIGGRAPH 99 (no kept Python package provides a sky model).

Sky: the CIE xyY of each direction from the Perez et al. (1993) distribution
F(theta, gamma) = (1 + A exp(B / cos theta)) (1 + C exp(D gamma) + E cos^2 gamma), with the
paper's coefficients linear in turbidity T (its Appendix A.2) and its zenith values: zenith
luminance Y_z = (4.0453 T - 4.9710) tan chi - 0.2155 T + 2.4192 kcd/m^2,
chi = (4/9 - T/120)(pi - 2 theta_s), zenith chromaticities x_z, y_z from the paper's
polynomials in T and theta_s. Y(theta, gamma) = Y_z F(theta, gamma) / F(0, theta_s), the same for
x and y; xyY -> XYZ -> linear sRGB (D65 white, no adaptation). Black below the horizon (the
scene's ground is geometry).

Sun: extraterrestrial sunlight as a 5778 K black body (its colour; 128 klx illuminance,
the solar illuminance constant), attenuated along the air mass m (Kasten 1966, as the
paper) by Rayleigh scattering exp(-0.008735 lambda^-4.08 m) and aerosols
exp(-beta lambda^-1.3 m), beta = 0.04608 T - 0.04586 (lambda in um) -- the paper's
Appendix A.1 without its ozone, water and mixed-gas absorption bands (a few per cent in
the visible). Spectral mode lights with that spectrum (``sun_spectrum``: relative to D65,
as every emitter spectrum, at the transmitted illuminance in klx); RGB mode with its RGB,
clipped to >= 0 (a low sun in haze has a negative sRGB blue).

Both are multiplied by the light's ``scale`` (default 0.05: a clear-sky ground of albedo
0.35 then comes out near radiance 0.5, the other scenes' range).
"""
from __future__ import annotations

import math

import numpy as np

from bsdflab.spectra import DEFAULT_WAVELENGTHS, spectrum_to_rgb

SKY_HEIGHT = 128
SOLAR_ILLUMINANCE_KLX = 128.0
SUN_TEMPERATURE_K = 5778.0
_LUMINANCE = np.array([0.2126, 0.7152, 0.0722])  # linear sRGB -> Y
# Perez coefficients (A..E) as (slope, intercept) in turbidity, Preetham et al. Appendix A.2.
_PEREZ_Y = np.array([[0.1787, -1.4630], [-0.3554, 0.4275], [-0.0227, 5.3251], [0.1206, -2.5771],
                     [-0.0670, 0.3703]])
_PEREZ_X = np.array([[-0.0193, -0.2592], [-0.0665, 0.0008], [-0.0004, 0.2125], [-0.0641, -0.8989],
                     [-0.0033, 0.0452]])
_PEREZ_YC = np.array([[-0.0167, -0.2608], [-0.0950, 0.0092], [-0.0079, 0.2102], [-0.0441, -1.6537],
                      [-0.0109, 0.0529]])
# Zenith chromaticity: [T^2, T, 1] M [theta_s^3, theta_s^2, theta_s, 1]^T.
_ZENITH_X = np.array([[0.00166, -0.00375, 0.00209, 0.0], [-0.02903, 0.06377, -0.03202, 0.00394],
                      [0.11693, -0.21196, 0.06052, 0.25886]])
_ZENITH_Y = np.array([[0.00275, -0.00610, 0.00317, 0.0], [-0.04214, 0.08970, -0.04153, 0.00516],
                      [0.15346, -0.26756, 0.06670, 0.26688]])
# sRGB from XYZ (IEC 61966-2-1, D65).
_XYZ_TO_SRGB = np.array([[3.2404542, -1.5371385, -0.4985314], [-0.9692660, 1.8760108, 0.0415560],
                         [0.0556434, -0.2040259, 1.0572252]])


def _perez(coeffs: np.ndarray, turbidity: float, cos_theta, gamma):
    a, b, c, d, e = coeffs[:, 0] * turbidity + coeffs[:, 1]
    return (1 + a * np.exp(b / cos_theta)) * (1 + c * np.exp(d * gamma) + e * np.cos(gamma) ** 2)


def _zenith(turbidity: float, theta_s: float) -> tuple[float, float, float]:
    chi = (4 / 9 - turbidity / 120) * (math.pi - 2 * theta_s)
    luminance = (4.0453 * turbidity - 4.9710) * math.tan(chi) - 0.2155 * turbidity + 2.4192
    t = np.array([turbidity**2, turbidity, 1.0])
    s = np.array([theta_s**3, theta_s**2, theta_s, 1.0])
    return float(luminance), float(t @ _ZENITH_X @ s), float(t @ _ZENITH_Y @ s)


def sky_radiance(directions, sun_direction, turbidity: float) -> np.ndarray:
    """Linear sRGB radiance (kcd/m^2 luminance units) of the Preetham sky towards unit
    ``directions`` (..., 3), +Y up; 0 at and below the horizon."""
    d = np.asarray(directions, dtype=float)
    sun = np.asarray(sun_direction, dtype=float)
    theta_s = math.acos(min(1.0, max(-1.0, sun[1])))
    cos_theta = d[..., 1]
    above = cos_theta > 0
    cos_t = np.where(above, cos_theta, 1.0)
    gamma = np.arccos(np.clip(d @ sun, -1.0, 1.0))
    y_z, x_z, yc_z = _zenith(turbidity, theta_s)
    gamma_s = theta_s  # the sun's own angle from the zenith

    def channel(coeffs, zenith):
        return zenith * _perez(coeffs, turbidity, cos_t, gamma) / _perez(coeffs, turbidity, 1.0, gamma_s)

    lum, x, y = channel(_PEREZ_Y, y_z), channel(_PEREZ_X, x_z), channel(_PEREZ_YC, yc_z)
    xyz = np.stack([x / y * lum, lum, (1 - x - y) / y * lum], axis=-1)
    rgb = np.maximum(xyz @ _XYZ_TO_SRGB.T, 0.0)
    return np.where(above[..., None], rgb, 0.0)


def sky_image(sun_direction, turbidity: float, scale: float = 1.0, height: int = SKY_HEIGHT) -> np.ndarray:
    """The sky as an (H, 2H, 3) lat-long image in the renderer's mapping (Environment):
    row j at theta = (j + 1/2) pi / H from +Y, column i at phi = (i + 1/2) 2 pi / W,
    direction (sin theta sin phi, cos theta, -sin theta cos phi)."""
    theta = (np.arange(height) + 0.5) * np.pi / height
    phi = (np.arange(2 * height) + 0.5) * np.pi / height
    st, ct = np.sin(theta)[:, None], np.cos(theta)[:, None]
    d = np.stack(np.broadcast_arrays(st * np.sin(phi), ct, -st * np.cos(phi)), axis=-1)
    return (scale * sky_radiance(d, sun_direction, turbidity)).astype(np.float32)


def air_mass(theta_s: float) -> float:
    """Relative optical air mass at zenith angle theta_s (Kasten 1966, Preetham's A.1)."""
    deg = math.degrees(theta_s)
    return 1.0 / (math.cos(theta_s) + 0.15 * (93.885 - deg) ** -1.253)


def sun_transmittance(wavelengths_nm, theta_s: float, turbidity: float) -> np.ndarray:
    lam = np.asarray(wavelengths_nm, dtype=float) / 1000.0
    m = air_mass(theta_s)
    beta = 0.04608 * turbidity - 0.04586
    return np.exp(-0.008735 * lam**-4.08 * m) * np.exp(-beta * lam**-1.3 * m)


def sky_sun(lights):
    """The ``sun`` light among ``lights`` that brings its sky (at most one), or None."""
    return next((lt for lt in lights if lt.type == "sun" and lt.sky), None)


def sun_spectrum(light) -> np.ndarray:
    """A ``sun`` light's irradiance spectrum on the renderer's bins (DEFAULT_WAVELENGTHS),
    relative to D65 as every emitter spectrum, scaled so that its luminance is the
    transmitted illuminance (klx x scale). Spectral mode lights with it."""
    import colour

    wl = DEFAULT_WAVELENGTHS
    theta_s = math.acos(min(1.0, light.sun_direction()[1]))
    body = colour.sd_blackbody(SUN_TEMPERATURE_K, colour.SpectralShape(360, 830, 1))
    ext = np.interp(wl, body.wavelengths, body.values)
    d65 = colour.SDS_ILLUMINANTS["D65"]
    rel = ext * sun_transmittance(wl, theta_s, light.turbidity) / np.interp(wl, d65.wavelengths, d65.values)
    # Illuminance after the atmosphere, relative to outside it (luminance-weighted).
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    ybar = np.interp(wl, cmfs.wavelengths, cmfs.values[:, 1])
    kept = float(np.sum(ybar * ext * sun_transmittance(wl, theta_s, light.turbidity)) / np.sum(ybar * ext))
    luminance = float(np.asarray(spectrum_to_rgb(rel, wl), dtype=float) @ _LUMINANCE)
    return light.scale * SOLAR_ILLUMINANCE_KLX * kept * rel / luminance


def sun_irradiance(light) -> np.ndarray:
    """Linear sRGB irradiance of a ``sun`` light on a surface facing it (klx x scale): the RGB
    of sun_spectrum, clipped to >= 0 (a low sun in haze is so red that its sRGB has a
    negative blue, which no light may carry; colour_of clips the same way)."""
    rgb = np.asarray(spectrum_to_rgb(sun_spectrum(light), DEFAULT_WAVELENGTHS), dtype=float)
    return np.maximum(rgb, 0.0)
