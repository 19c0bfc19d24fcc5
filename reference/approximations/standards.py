"""What the material standards let a thin film be, and whether the snake's film fits.

Parameter ranges as the specifications publish them (hard limits; "soft" = the UI range the
spec recommends, values outside it are still legal). The snake's film (bsdflab.presets):
guanine n = 1.83, 400 nm (the paper sweeps 300-1200 nm), on keratin n = 1.5515.
"""
from __future__ import annotations

import math

SNAKE_FILM = {"film_ior": 1.83, "thickness_nm": 400.0, "thickness_sweep_nm": (300.0, 1200.0), "base_ior": 1.5515}

# name -> (thickness range nm (lo, hi; inf = unbounded), film index range, how the base index is given,
#          which comparison model implements it)
STANDARDS = {
    "glTF KHR_materials_iridescence": {
        "thickness_nm": (0.0, math.inf), "thickness_note": "iridescenceThicknessMinimum/Maximum (defaults 100 / 400 nm)"
                                                           " with a texture between them",
        "film_ior": (1.0, math.inf), "film_note": "iridescenceIor, default 1.3",
        "base": "KHR_materials_ior (F0 from the index; Schlick)", "model": "glTF KHR_materials_iridescence"},
    "OpenPBR Surface 1.x": {
        "thickness_nm": (0.0, math.inf), "thickness_note": "thin_film_thickness in micrometres (soft 0-1 um)",
        "film_ior": (1.0, math.inf), "film_note": "thin_film_ior (soft 1-3)",
        "base": "specular_ior",
        "model": "Belcour-Barla as MaterialX computes it (MaterialX, OpenPBR, Standard Surface)"},
    "Autodesk Standard Surface 1.0": {
        "thickness_nm": (0.0, math.inf), "thickness_note": "thin_film_thickness in nm (soft 0-2000 nm)",
        "film_ior": (1.0, math.inf), "film_note": "thin_film_IOR (soft 1-3)",
        "base": "specular_IOR",
        "model": "Belcour-Barla as MaterialX computes it (MaterialX, OpenPBR, Standard Surface)"},
    "MaterialX thin_film_bsdf": {
        "thickness_nm": (0.0, math.inf), "thickness_note": "thickness in nm", "film_ior": (1.0, math.inf),
        "film_note": "ior", "base": "the layered dielectric/conductor BSDF's ior",
        "model": "Belcour-Barla as MaterialX computes it (MaterialX, OpenPBR, Standard Surface)"},
    "Blender Principled BSDF (>= 4.2)": {
        "thickness_nm": (0.0, 100000.0), "thickness_note": "Thin Film Thickness in nm",
        "film_ior": (1.0, math.inf), "film_note": "Thin Film IOR", "base": "IOR input",
        "model": "Cycles thin film (Blender >= 4.2: CIE tables, 3 terms)"},
}


def can_represent(standard: dict, film=SNAKE_FILM) -> bool:
    lo, hi = standard["thickness_nm"]
    f_lo, f_hi = standard["film_ior"]
    return (lo <= film["thickness_sweep_nm"][0] and film["thickness_sweep_nm"][1] <= hi
            and f_lo <= film["film_ior"] <= f_hi)
