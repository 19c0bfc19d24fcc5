"""The few optics formulas the comparison models share, written out so that they stay
independent of bsdflab's core (numpy only, real dielectric indices)."""
from __future__ import annotations

import numpy as np

# linear sRGB (D65) from CIE XYZ: the IEC 61966-2-1 matrix that shaders use (glTF's
# XYZ_TO_REC709, MaterialX's XYZ_TO_RGB).
XYZ_TO_SRGB = np.array([[3.2404542, -1.5371385, -0.4985314],
                        [-0.9692660, 1.8760108, 0.0415560],
                        [0.0556434, -0.2040259, 1.0572252]])


def refracted_cos(n_i, n_t, cos_i):
    """cos(theta_t) by Snell's law; NaN past total internal reflection."""
    sin2 = (np.asarray(n_i) / np.asarray(n_t)) ** 2 * (1.0 - np.asarray(cos_i) ** 2)
    with np.errstate(invalid="ignore"):
        return np.where(sin2 <= 1.0, np.sqrt(np.maximum(1.0 - sin2, 0.0)), np.nan)


def dielectric_amplitudes(n_i, n_t, cos_i, cos_t):
    """Signed Fresnel amplitudes (r_s, r_p) of a real interface (Born & Wolf signs, as tmm)."""
    r_s = (n_i * cos_i - n_t * cos_t) / (n_i * cos_i + n_t * cos_t)
    r_p = (n_t * cos_i - n_i * cos_t) / (n_t * cos_i + n_i * cos_t)
    return r_s, r_p
