"""A three-wavelength "RGB": kept only to show why bsdflab does not use it.

The snake-skin model of Padrón-Griffe et al. ("A biologically-inspired appearance model
for snake skin", CEIG 2023) computes a thin film's colour by evaluating its reflectance
at one wavelength per RGB channel and using the three numbers directly as R, G and B. Its
public implementation (Mitsuba 0.6 plugins, ``dielectricThinFilm.cpp``) uses 650 nm,
510 nm and 475 nm, which `THREE_WAVELENGTHS_NM` copies.

Why it aliases
--------------
A film of index n1 and thickness d reflects with fringes whose period in wavelength is
about lambda^2 / (2 n1 d cos theta_1): ~210 nm at 550 nm for 400 nm of guanine
(n1 = 1.83), but ~70 nm for 1200 nm. The eye (the CIE colour-matching functions)
averages the spectrum over each channel's ~100 nm wide band, so once several fringes
fall inside a band they cancel and a thick film looks pale or grey. Three point samples cannot see that: each
lands on a peak or a trough by chance, so the "RGB" keeps cycling through saturated
colours with thickness and angle, at a rate set by the sample spacing rather than by the
optics -- the colour is aliased. Even for a thin film the three samples miss the
spectrum's shape between them, and the numbers are not sRGB in any colorimetric sense.

bsdflab's default instead integrates the full reflectance spectrum against the CIE 1931
observer under D65 (`bsdflab.spectra.spectrum_to_rgb` on `DEFAULT_WAVELENGTHS` or a finer
grid). For a spectrally flat reflectance both agree, because that matrix maps a constant
spectrum v to (v, v, v) exactly.
"""
from __future__ import annotations

import numpy as np

from bsdflab.util.args import real_array

# (R, G, B) sample wavelengths in nm, as in Padrón-Griffe et al. 2023's public code.
THREE_WAVELENGTHS_NM = (650.0, 510.0, 475.0)


def three_wavelength_rgb(values_at_three) -> np.ndarray:
    """The naive "linear RGB": the spectrum's values at three wavelengths.

    Parameters
    ----------
    values_at_three : array_like, shape (..., 3)
        A spectrum (e.g. a reflectance, dimensionless) evaluated at
        `THREE_WAVELENGTHS_NM`, in that order (650, 510, 475 nm); finite.

    Returns
    -------
    ndarray, shape (..., 3)
        The same numbers taken as R, G, B -- what the three-wavelength renderer shows. For comparison with
        `spectrum_to_rgb` only; see the module docstring for why it aliases.

    Raises
    ------
    ValueError
        If the last axis is not of length 3 or a value is not finite.
    """
    v = real_array("values_at_three", values_at_three)
    if v.shape[-1:] != (3,):
        raise ValueError(f"values_at_three must end in an axis of 3 (values at "
                         f"{THREE_WAVELENGTHS_NM} nm), got shape {v.shape}")
    return v.copy()
