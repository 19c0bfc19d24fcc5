"""Comparison-only models of thin-film iridescence used by other tools (never bsdflab materials).

These reproduce, from their published specifications, the approximations that renderers and
material standards use for a single thin film, so that `bsdflab validate` can say how far
each is from the exact spectral Airy reflectance (`bsdflab.optics.thin_film`):

``belcour_barla``   Belcour & Barla 2017, "A practical extension to microfacet theory for the
                    modeling of varying iridescence" (ACM TOG 36(4)): the Airy sum reordered
                    as a Fourier series in the optical path difference, integrated in closed
                    form against Gaussian fits of the CIE XYZ sensitivities, returned in
                    linear sRGB. This is the formulation of MaterialX's ``thin_film_bsdf``
                    (``mx_fresnel_airy``), hence OpenPBR Surface's and Autodesk Standard
                    Surface's thin film in MaterialX (exact s/p Fresnel, two series terms).
``cycles``          Blender Cycles >= 4.2 (Principled BSDF "Thin Film"), from Cycles' source:
                    the same series with three terms and tabulated Fourier transforms of the
                    CIE 1931 colour-matching functions instead of the Gaussian fit; held to
                    real bpy renders (tests/export/test_cycles_thin_film.py).
``gltf``            glTF ``KHR_materials_iridescence`` (Khronos, 2022, appendix "Implementation"):
                    the same series with Schlick's Fresnel approximation, phases 0 or pi, two
                    terms, the base index recovered from F0, negative colours clamped.
``double_phase_film``  The snake-skin paper's public code (Padrón-Griffe et al., CEIG 2023,
                    Mitsuba 0.6 ``dielectricThinFilm``): the Airy sum with an extra reflection
                    phase on top of signed amplitudes (counted twice) at three wavelengths
                    taken as RGB.

Every function returns linear sRGB (D65) reflectance, shape (..., 3), for unpolarised light,
so the colour-difference study (``study.py``) compares them all in the same space.
"""
from bsdflab.reference.approximations._optics import XYZ_TO_SRGB  # the shared sRGB matrix
from bsdflab.reference.approximations.belcour_barla import (
    belcour_barla_rgb,
    belcour_barla_xyz,
    xyz_sensitivity_exact,
    xyz_sensitivity_gaussian,
)
from bsdflab.reference.approximations.cycles import cycles_thin_film_rgb
from bsdflab.reference.approximations.double_phase_film import double_phase_reflectance, double_phase_rgb
from bsdflab.reference.approximations.gltf import gltf_iridescence_rgb

MATERIALX = "Belcour-Barla as MaterialX computes it (MaterialX, OpenPBR, Standard Surface)"
CYCLES = "Cycles thin film (Blender >= 4.2: CIE tables, 3 terms)"
MODELS = {
    MATERIALX: belcour_barla_rgb,
    CYCLES: cycles_thin_film_rgb,
    "Belcour-Barla fit alone (XYZ to sRGB with E to D65)":
        lambda *a: belcour_barla_rgb(*a, sensitivity="gaussian-srgb"),
    "glTF KHR_materials_iridescence": gltf_iridescence_rgb,
    "Padrón-Griffe et al. 2023 code (double phase, 3 wavelengths)": double_phase_rgb,
}

__all__ = ["CYCLES", "MATERIALX", "MODELS", "XYZ_TO_SRGB", "belcour_barla_rgb", "belcour_barla_xyz",
           "cycles_thin_film_rgb", "double_phase_reflectance", "double_phase_rgb", "gltf_iridescence_rgb",
           "xyz_sensitivity_exact", "xyz_sensitivity_gaussian"]
