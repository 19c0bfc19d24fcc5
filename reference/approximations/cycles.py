"""Blender Cycles' thin film (Principled BSDF "Thin Film", Blender >= 4.2): what Cycles computes.

Comparison model (not a bsdflab material), written from Cycles' own source, read as a
specification (Blender 5.0: ``intern/cycles/kernel/closure/bsdf_util.h``,
``fresnel_iridescence`` and ``iridescence_airy_summation``; ``intern/cycles/scene/shader.cpp``,
``compute_thin_film_table``). Cycles follows Belcour & Barla 2017 (see belcour_barla.py) but
differs from the paper's shader (and from MaterialX / OpenPBR's ``mx_fresnel_airy``) in
three ways that change colours visibly:

1. **Sensitivities are not the Gaussian fit.** Cycles tabulates the Fourier transform of the
   CIE 1931 2-degree colour-matching functions resampled on a uniform grid in frequency
   (1 / lambda), turns XYZ into the scene-linear space with the D65 XYZ -> Rec.709 matrix
   (the default scene-linear space), and divides each RGB channel by its DC term, so a
   flat reflectance of 1 gives (1, 1, 1) (illuminant E is white). The table spans optical
   path differences 0 .. 60000 / (2 pi) nm in 512 steps, read with linear interpolation and
   clamped at its end.
2. **Three harmonics** of the Airy series (m = 1, 2, 3), not two.
3. The s and p sums are averaged, then clamped to [0, 1] ("saturate"). Films thinner than
   1 nm blend the film index towards the outside's (smoothstep over 0-1 nm).

Fresnel amplitudes and phases are exact (s and p, 0 or pi for real indices), as in the paper.
``jacobian`` chooses how the CMFs are resampled in frequency: True (default) integrates
cmf(lambda) d lambda = cmf(1 / nu) d nu / nu^2, False the values resampled without the change
of variable. Cycles' precomputed table holds the former: against bpy 5.0.1 renders
(tests/export/test_cycles_thin_film.py) the default is within 0.0032 (RMS 0.0005) of Cycles'
pixels for theta <= 58 deg, the other resampling up to 0.012 off, MaterialX's model 0.01.
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np

from bsdflab.reference.approximations._optics import XYZ_TO_SRGB, refracted_cos
from bsdflab.reference.approximations.belcour_barla import _series

TABLE_SIZE = 512
TABLE_MAX_OPD_NM = 60000.0 / (2.0 * np.pi)
TERMS = 3


@lru_cache(maxsize=2)
def sensitivity_table(jacobian: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """(OPD grid in nm (512,), real part of the RGB sensitivity (512, 3)), each channel
    normalised to 1 at OPD 0: S_c(D) = int cmf_c cos(2 pi D nu) d nu / int cmf_c d nu."""
    import colour

    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    wl = cmfs.wavelengths.astype(float)
    nu = np.linspace(1.0 / wl[-1], 1.0 / wl[0], 4096)          # 1/nm, uniform in frequency
    xyz = np.stack([np.interp(1.0 / nu, wl, cmfs.values[:, k]) for k in range(3)])
    if jacobian:                                                # d lambda = d nu / nu^2
        xyz = xyz / nu**2
    rgb = XYZ_TO_SRGB @ xyz                                     # (3, F)
    opd = np.linspace(0.0, TABLE_MAX_OPD_NM, TABLE_SIZE)
    w = np.gradient(nu)                                         # quadrature weights (uniform grid)
    re = (rgb[None] * np.cos(2.0 * np.pi * opd[:, None, None] * nu)) @ w
    return opd, re / re[0]


def _lookup(opd_nm, jacobian: bool) -> np.ndarray:
    grid, table = sensitivity_table(jacobian)
    d = np.clip(np.asarray(opd_nm, float), 0.0, grid[-1])
    return np.stack([np.interp(d, grid, table[:, c]) for c in range(3)], axis=-1)


def cycles_thin_film_rgb(n_outer, n_film, n_base, thickness_nm, cos_theta, *, jacobian: bool = True,
                         terms: int = TERMS) -> np.ndarray:
    """Linear Rec.709 reflectance (..., 3) of Cycles' thin-film Fresnel for a dielectric base;
    arguments as ``belcour_barla_rgb`` (they broadcast). Total internal reflection gives 1.

    The series is Belcour-Barla's (``belcour_barla._series``); the phases are 0 or pi, so
    Cycles' complex table enters only through its real part: S(D, phi) = cos(phi) Re S(D)."""
    n1, n2, n3, d, c1 = np.broadcast_arrays(*(np.asarray(a, float) for a in
                                              (n_outer, n_film, n_base, thickness_nm, cos_theta)))
    t = np.clip(d, 0.0, 1.0)
    n2 = np.where(d < 1.0, n1 + (n2 - n1) * t * t * (3.0 - 2.0 * t), n2)   # films under 1 nm fade out

    def sensitivity(opd, shift):
        return np.cos(shift)[..., None] * _lookup(opd, jacobian)

    rgb = np.clip(_series(n1, n2, n3, d, c1, terms, sensitivity), 0.0, 1.0)
    return np.where(np.isnan(refracted_cos(n1, n3, c1))[..., None], 1.0, rgb)
