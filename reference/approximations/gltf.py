"""glTF 2.0 ``KHR_materials_iridescence``: the thin film as the Khronos extension specifies it.

Comparison model (not a bsdflab material). Specification: Khronos Group,
KHR_materials_iridescence (2022), section "Implementation" (``evalIridescence``). Its
simplifications of Belcour & Barla 2017 (see belcour_barla.py): Schlick's approximation
F0 + (1 - F0)(1 - cos)^5 for both interfaces, unpolarised; reflection phases 0 or pi from
comparing indices; the base's index recovered from its F0 = ((n - 1) / (n + 1))^2
(KHR_materials_ior, outside index 1); the film's index blended towards the outside's for
thicknesses below 0.03 (the spec's smoothstep(0, 0.03, thickness), thickness in nm); the same Gaussian XYZ fit, two
harmonics, R12 R23 clamped to [1e-5, 0.9999] and negative colours clamped to 0; total internal reflection in the film
gives 1.
"""
from __future__ import annotations

import numpy as np

from bsdflab.reference.approximations._optics import XYZ_TO_SRGB
from bsdflab.reference.approximations.belcour_barla import xyz_sensitivity_gaussian


def _schlick(f0, cos):
    return f0 + (1.0 - f0) * (1.0 - cos) ** 5


def _ior_to_f0(n_t, n_i):
    return ((n_t - n_i) / (n_t + n_i)) ** 2


def _f0_to_ior(f0):
    s = np.sqrt(np.clip(f0, 0.0, 0.9999))
    return (1.0 + s) / (1.0 - s)


def gltf_iridescence_rgb(n_outer, n_film, n_base, thickness_nm, cos_theta) -> np.ndarray:
    """Linear sRGB (Rec. 709) reflectance (..., 3), arguments as
    ``belcour_barla_rgb``; the base index enters through its F0 as a glTF material's would."""
    n1, n2, n3, d, c1 = np.broadcast_arrays(*(np.asarray(a, float) for a in
                                              (n_outer, n_film, n_base, thickness_nm, cos_theta)))
    t = np.clip(d / 0.03, 0.0, 1.0)
    eta2 = n1 + (n2 - n1) * t * t * (3.0 - 2.0 * t)      # mix(outside, ior, smoothstep)
    sin2 = (n1 / eta2) ** 2 * (1.0 - c1**2)
    tir = sin2 > 1.0
    c2 = np.sqrt(np.clip(1.0 - sin2, 0.0, 1.0))
    R12 = _schlick(_ior_to_f0(eta2, n1), c1)
    T121 = 1.0 - R12
    phi12 = np.where(eta2 < n1, np.pi, 0.0)
    phi21 = np.pi - phi12
    base = _f0_to_ior(_ior_to_f0(n3, 1.0))
    R23 = _schlick(_ior_to_f0(base, eta2), c2)
    phi23 = np.where(base < eta2, np.pi, 0.0)
    opd = 2.0 * eta2 * d * c2
    phi = phi21 + phi23
    R123 = np.clip(R12 * R23, 1e-5, 0.9999)
    Rs = T121**2 * R23 / (1.0 - R123)
    I = (R12 + Rs)[..., None] * np.ones(3)
    Cm = Rs - T121
    for m in (1, 2):
        Cm = Cm * np.sqrt(R123)
        I = I + Cm[..., None] * 2.0 * (xyz_sensitivity_gaussian(m * opd, m * phi) @ XYZ_TO_SRGB.T)
    return np.where(tir[..., None], 1.0, np.maximum(I, 0.0))
