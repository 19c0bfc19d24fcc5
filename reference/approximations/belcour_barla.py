"""Belcour & Barla 2017: Airy reflectance of one thin film, spectrally pre-integrated, in RGB.

Comparison model (not a bsdflab material). Specification: L. Belcour, P. Barla, "A practical
extension to microfacet theory for the modeling of varying iridescence", ACM TOG 36(4) 65,
2017, section 4 and its supplemental shader; the same formulation is the thin film of
MaterialX (``thin_film_bsdf`` / ``mx_fresnel_airy``), through which OpenPBR Surface and
Autodesk Standard Surface are rendered. Blender Cycles >= 4.2 computes a different variant
(tabulated CIE sensitivities, three terms): see cycles.py.

The model. Media 1 (outside), 2 (film, thickness d) and 3 (base), real indices here. Per
polarisation, with R12 = |r12|^2, T121 = 1 - R12, R23 = |r23|^2, phases phi21 = pi - phi12
and phi23 (0 or pi for dielectrics: the signs of the amplitudes), the Airy reflectance is
the Fourier series in the phase Phi = 2 pi D / lambda + phi21 + phi23, D = 2 n2 d cos(theta2)
the optical path difference:

    R(lambda) = C0 + 2 sum_{m >= 1} C_m cos(m Phi),
    C0 = R12 + Rs,  Rs = T121^2 R23 / (1 - R12 R23),  C_m = (Rs - T121) (R12 R23)^(m / 2).

Integrated against colour-matching functions, each cosine becomes a "sensitivity"
S(m D, m phi) = int cmf(lambda) cos(2 pi m D / lambda + m phi) dlambda, which the paper
approximates in closed form by Gaussians fitted to the CIE XYZ sensitivities in the Fourier
domain (``xyz_sensitivity_gaussian``; the constants are the paper's). The series is cut
after ``terms`` harmonics (MaterialX: 2). As in MaterialX's ``mx_fresnel_airy``, the sum is
accumulated in XYZ (the constant term as C0 (1, 1, 1)), s and p are averaged, and XYZ goes
to RGB with the CIE 1931 RGB matrix (illuminant E, so white stays white), clamped to [0, 1];
a renderer then uses those numbers as its working-space (here linear sRGB) reflectance.

``sensitivity="exact"`` replaces the Gaussian fit with the exact integral on a 1 nm grid
against bsdflab's D65 -> linear sRGB weights; with many terms the series then equals the
exact spectral result to round-off (tested): what remains in the default model is exactly
its two approximations, the Gaussian fit and the truncation.
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np

from bsdflab.reference.approximations._optics import dielectric_amplitudes, refracted_cos

# XYZ -> CIE 1931 RGB (equal-energy white), as MaterialX's mx_fresnel_airy uses.
XYZ_TO_CIE_RGB = np.array([[2.3706743, -0.9000405, -0.4706338],
                           [-0.5138850, 1.4253036, 0.0885814],
                           [0.0052982, -0.0146949, 1.0093968]])

# Gaussian fits of the XYZ sensitivities (Belcour & Barla 2017, supplemental code):
# amplitude, centre (1/m) and variance of each Gaussian; x has a second lobe.
_GAUSS_VAL = np.array([5.4856e-13, 4.4201e-13, 5.2481e-13])
_GAUSS_POS = np.array([1.6810e06, 1.7953e06, 2.2084e06])
_GAUSS_VAR = np.array([4.3278e09, 9.3046e09, 6.6121e09])
_X2 = (9.7470e-14, 2.2399e06, 4.5282e09)
_NORMALISATION = 1.0685e-7  # makes S(0, 0) = (1, 1, 1) in XYZ


def xyz_sensitivity_gaussian(opd_nm, shift) -> np.ndarray:
    """The paper's closed-form XYZ sensitivity, shape (..., 3), for an optical path
    difference in nm and a phase shift in radians (broadcast)."""
    phase = 2.0 * np.pi * np.asarray(opd_nm, float)[..., None] * 1e-9
    shift = np.asarray(shift, float)[..., None]
    xyz = (_GAUSS_VAL * np.sqrt(2.0 * np.pi * _GAUSS_VAR) * np.cos(_GAUSS_POS * phase + shift)
           * np.exp(-_GAUSS_VAR * phase**2))
    v, pos, var = _X2
    x2 = (v * np.sqrt(2.0 * np.pi * var) * np.cos(pos * phase[..., 0] + shift[..., 0])
          * np.exp(-var * phase[..., 0] ** 2))
    xyz = xyz + np.stack([x2, np.zeros_like(x2), np.zeros_like(x2)], axis=-1)
    return xyz / _NORMALISATION


@lru_cache(maxsize=1)
def _exact_weights():
    from bsdflab.spectra import srgb_weights

    wl = np.arange(380.0, 781.0, 1.0)
    return wl, srgb_weights(wl)


def xyz_sensitivity_exact(opd_nm, shift) -> np.ndarray:
    """The exact sensitivity in linear sRGB (D65), shape (..., 3): sum over a 1 nm grid of
    the sRGB weights times cos(2 pi D / lambda + shift). S(0, 0) = (1, 1, 1)."""
    wl, W = _exact_weights()
    arg = 2.0 * np.pi * np.asarray(opd_nm, float)[..., None] / wl + np.asarray(shift, float)[..., None]
    return np.cos(arg) @ W.T


@lru_cache(maxsize=1)
def _xyz_e_to_srgb() -> np.ndarray:
    """XYZ under illuminant E -> linear sRGB (D65) with a Bradford adaptation E -> D65."""
    import colour

    from bsdflab.spectra.colour_weights import rgb_colourspace

    cs = rgb_colourspace()
    cat = colour.adaptation.matrix_chromatic_adaptation_VonKries(
        np.ones(3), colour.xy_to_XYZ(cs.whitepoint), transform="Bradford")
    return cs.matrix_XYZ_to_RGB @ cat


def _sensitivity(kind: str):
    """(sensitivity in the accumulation space, matrix to RGB or None, clamp?)"""
    if kind == "gaussian":
        return xyz_sensitivity_gaussian, XYZ_TO_CIE_RGB, True
    if kind == "gaussian-srgb":
        return xyz_sensitivity_gaussian, _xyz_e_to_srgb(), False
    if kind == "exact":
        return xyz_sensitivity_exact, None, False
    raise ValueError(f"sensitivity must be 'gaussian', 'gaussian-srgb' or 'exact', got {kind!r}")


def belcour_barla_xyz(n_outer, n_film, n_base, thickness_nm, cos_theta, *, terms: int = 2) -> np.ndarray:
    """CIE XYZ (illuminant E, Y of a perfect reflector = 1), shape (..., 3), of the film
    with the paper's Gaussian sensitivities: the quantity the paper integrates in closed
    form, before any RGB conversion. Arguments as ``belcour_barla_rgb``."""
    return _series(n_outer, n_film, n_base, thickness_nm, cos_theta, terms, xyz_sensitivity_gaussian)


def belcour_barla_rgb(n_outer, n_film, n_base, thickness_nm, cos_theta, *, terms: int = 2,
                      sensitivity: str = "gaussian") -> np.ndarray:
    """Linear RGB reflectance (..., 3) of a film of index ``n_film`` and thickness
    ``thickness_nm`` between real media ``n_outer`` (light's side) and ``n_base``, for light
    arriving at ``cos_theta`` (in the outer medium); arguments broadcast.

    terms : harmonics kept (>= 1); sensitivity : "gaussian" (the paper's fit, MaterialX's
    CIE RGB), "gaussian-srgb" (the same fit, XYZ taken to linear sRGB with a Bradford
    adaptation E -> D65: the fit's error without MaterialX's colour-space shortcut) or
    "exact" (linear sRGB, D65). Total internal reflection at the film returns 1.
    """
    S, to_rgb, clamp = _sensitivity(sensitivity)
    rgb = _series(n_outer, n_film, n_base, thickness_nm, cos_theta, terms, S)
    if to_rgb is not None:
        rgb = rgb @ to_rgb.T
    return np.clip(rgb, 0.0, 1.0) if clamp else rgb


def _series(n_outer, n_film, n_base, thickness_nm, cos_theta, terms, S) -> np.ndarray:
    """The Fourier series averaged over s and p, in the space of the sensitivity S."""
    if int(terms) != terms or terms < 1:
        raise ValueError(f"terms must be an integer >= 1, got {terms!r}")
    n1, n2, n3, d, c1 = np.broadcast_arrays(*(np.asarray(a, float) for a in
                                              (n_outer, n_film, n_base, thickness_nm, cos_theta)))
    c2 = refracted_cos(n1, n2, c1)
    c3 = refracted_cos(n1, n3, c1)
    tir = np.isnan(c2)
    c2, c3 = np.nan_to_num(c2, nan=1.0), np.nan_to_num(c3, nan=0.0)
    opd = 2.0 * n2 * d * c2
    out = np.zeros(n1.shape + (3,))
    for r12, r23 in zip(dielectric_amplitudes(n1, n2, c1, c2), dielectric_amplitudes(n2, n3, c2, c3)):
        R12, R23 = r12**2, r23**2
        T121 = 1.0 - R12
        phi21 = np.pi - np.where(r12 < 0, np.pi, 0.0)
        phi2 = phi21 + np.where(r23 < 0, np.pi, 0.0)
        R123 = R12 * R23
        Rs = T121**2 * R23 / (1.0 - R123)
        I = (R12 + Rs)[..., None] * np.ones(3)
        Cm = Rs - T121
        for m in range(1, int(terms) + 1):
            Cm = Cm * np.sqrt(R123)
            I = I + Cm[..., None] * 2.0 * S(m * opd, m * phi2)
        out += 0.5 * I
    return np.where(tir[..., None], 1.0, out)
