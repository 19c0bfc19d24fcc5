"""Cycles' thin film as a comparison BSDF that bsdflab's renderer can render (not a product material).

``cycles_thin_film_comparison`` (``model="cycles"``): an opaque smooth surface whose specular reflectance is
``cycles_thin_film_rgb`` (what Blender's Principled BSDF with a black base, no transmission
and a Thin Film computes), tabulated on 1025 values of |cos theta| and interpolated linearly
by the core's ``TabulatedTerm``. It answers in linear sRGB (three channels), so a scene can
hold it beside the exact material and the path tracer renders both the same way. Registered
in the BSDF registry when this module is imported (``bsdflab.reference`` is a leaf: product
code never imports it).
"""
from __future__ import annotations

from typing import Any

import numpy as np

from bsdflab import _core
from bsdflab.bsdfs.base import BSDF
from bsdflab.reference.approximations.cycles import cycles_thin_film_rgb
from bsdflab.util import args as check

ROWS = 1025
RGB_LABEL_NM = np.array([610.0, 550.0, 465.0])   # the core's channel labels: the RGB primaries' dominant lines


class CyclesThinFilmComparison(BSDF):
    """Cycles' thin-film Fresnel on a black, opaque base (linear sRGB).

    Parameters
    ----------
    film_ior, base_ior : float in [1, 3]
        Thin Film IOR and the Principled BSDF's IOR (relative to the outside, n = 1).
    film_thickness_nm : float in [0, 1e5]
        Thin Film Thickness (nm).
    model : "cycles" or "exact"
        Whose reflectance: Cycles' approximation, or bsdflab's exact Airy film (spectral,
        D65 -> linear sRGB; ``approximations.study.exact_rgb``) on the same opaque base, so
        that both render through the same table and path tracer.
    """

    type_name = "cycles_thin_film_comparison"

    def __init__(self, film_ior: float, base_ior: float, film_thickness_nm: float, model: str = "cycles"):
        super().__init__()
        self.film_ior = check.real_scalar("film_ior", film_ior, 1.0, 3.0)
        self.base_ior = check.real_scalar("base_ior", base_ior, 1.0, 3.0)
        self.film_thickness_nm = check.real_scalar("film_thickness_nm", film_thickness_nm, 0.0, 1e5)
        if model not in ("cycles", "exact"):
            raise ValueError(f"model must be 'cycles' or 'exact', got {model!r}")
        self.model = model

    def reflectance(self, cos_theta) -> np.ndarray:
        """(..., 3) linear sRGB specular reflectance at cos theta."""
        if self.model == "exact":
            from bsdflab.reference.approximations.study import exact_rgb

            c = np.maximum(np.asarray(cos_theta, float), 1e-6)
            return exact_rgb(1.0, self.film_ior, self.base_ior, self.film_thickness_nm, c)
        return cycles_thin_film_rgb(1.0, self.film_ior, self.base_ior, self.film_thickness_nm, cos_theta)

    def _build(self, wavelengths: np.ndarray):
        table = np.clip(self.reflectance(np.linspace(0.0, 1.0, ROWS)), 0.0, 1.0)
        return _core.SmoothInterface(list(RGB_LABEL_NM), _core.TabulatedTerm(table.tolist()), True)

    def _channels(self, wavelengths):
        return RGB_LABEL_NM, None          # answers in RGB whatever grid is asked for

    def render_core(self):
        return self._core(RGB_LABEL_NM), None

    def _params(self) -> dict[str, Any]:
        return {"film_ior": self.film_ior, "base_ior": self.base_ior, "film_thickness_nm": self.film_thickness_nm,
                "model": self.model}
