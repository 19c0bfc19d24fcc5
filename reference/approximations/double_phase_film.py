"""A thin film with a double-counted reflection phase, three wavelengths taken as RGB.

Comparison model (not a bsdflab material) of the thin-film formula in the public Mitsuba 0.6
code of Padrón-Griffe et al., "A biologically-inspired appearance model for snake skin"
(CEIG 2023, doi:10.2312/CEIG.20231143; plugin ``dielectricThinFilm``): the Airy sum of
signed Fresnel amplitudes, plus a reflection phase pi for the top reflection when the film
is denser than the outside -- a phase the sign of r01 already carries, so it is counted
twice -- evaluated at 650, 510 and 475 nm and used directly as R, G, B
(`bsdflab.spectra.three_wavelength`). Worked counter-example (n = 1 / 1.56 / 1.83,
d = 400 nm, 475 nm, 0.4 rad): this formula gives R = 0.0854 where the exact value (tmm,
bsdflab) is 0.0218 (tested; docs/validation.md).
"""
from __future__ import annotations

import numpy as np

from bsdflab.reference.approximations._optics import dielectric_amplitudes, refracted_cos
from bsdflab.spectra.three_wavelength import THREE_WAVELENGTHS_NM, three_wavelength_rgb


def double_phase_reflectance(n0, n1, n2, thickness_nm, wavelength_nm, cos_theta) -> np.ndarray:
    """Unpolarised film reflectance with the doubled phase (broadcast over all arguments)."""
    n0, n1, n2, d, wl, c0 = np.broadcast_arrays(*(np.asarray(a, float) for a in
                                                  (n0, n1, n2, thickness_nm, wavelength_nm, cos_theta)))
    c1 = refracted_cos(n0, n1, c0)
    c2 = refracted_cos(n0, n2, c0)
    tir = np.isnan(c1)
    c1, c2 = np.nan_to_num(c1, nan=1.0), np.nan_to_num(c2, nan=0.0)
    phase = np.exp(2j * (2.0 * np.pi * n1 * d * c1 / wl))
    extra = np.where(n1 > n0, -1.0, 1.0)  # e^{i pi}: the phase counted a second time
    R = 0.0
    for r01, r12 in zip(dielectric_amplitudes(n0, n1, c0, c1), dielectric_amplitudes(n1, n2, c1, c2), strict=True):
        a = r01 * extra
        R = R + 0.5 * np.abs((a + r12 * phase) / (1.0 + a * r12 * phase)) ** 2
    return np.where(tir, 1.0, R)


def double_phase_rgb(n_outer, n_film, n_base, thickness_nm, cos_theta) -> np.ndarray:
    """The formula's "RGB" (..., 3): its reflectance at 650, 510 and 475 nm."""
    args = [np.asarray(a, float)[..., None] for a in (n_outer, n_film, n_base, thickness_nm)]
    c = np.asarray(cos_theta, float)[..., None]
    return three_wavelength_rgb(double_phase_reflectance(*args, np.array(THREE_WAVELENGTHS_NM), c))
