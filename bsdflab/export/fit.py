"""Fit a target standard's thin-film parameters to bsdflab's exact film, by CIEDE2000.

What is matched: the specular (thin-film Fresnel) colour as a function of the incidence
angle, over the material's film-thickness spread. The exact side is bsdflab's spectral Airy
reflectance of the film (``bsdflab.optics``, 1 nm grid, D65 -> linear sRGB); the target
side is the standard's own model (``bsdflab.export.targets``). Both are taken at every
(angle, scale) of the grid, where a scale s in [1 - SPREAD, 1 + SPREAD] multiplies the film
thickness on both sides (the snake's per-scale thickness variation: an exported thickness
texture carries the same factor). The fitted parameters are (film thickness, film index,
base index) within the target's ranges, minimising the mean Delta E00 over the grid:
a coarse grid over thickness and film index, then Nelder-Mead from its best point.

The diffuse body colour is fitted after this, at these parameters (``bsdflab.export.body``).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bsdflab.export.material import SPREAD, ExportMaterial
from bsdflab.export.targets import Target

ANGLES_DEG = np.linspace(0.0, 80.0, 17)
SCALES = np.linspace(1.0 - SPREAD, 1.0 + SPREAD, 7)
TARGET_OUTER_IOR = 1.0   # every target assumes the surface is seen from vacuum / air at n = 1


@dataclass
class FitResult:
    thickness_nm: float
    film_ior: float
    base_ior: float
    angles_deg: np.ndarray        # (A,)
    scales: np.ndarray            # (S,)
    exact_rgb: np.ndarray         # (A, S, 3)
    target_rgb: np.ndarray        # (A, S, 3)
    delta_e: np.ndarray           # (A, S)

    def summary(self) -> dict:
        e = self.delta_e
        return {"median": float(np.median(e)), "mean": float(e.mean()), "max": float(e.max()),
                "share_above_1": float(np.mean(e > 1.0)), "share_above_2": float(np.mean(e > 2.0))}


def _grid(angles_deg, scales):
    cos = np.cos(np.radians(angles_deg))[:, None] * np.ones(len(scales))[None, :]
    return cos, np.ones(len(angles_deg))[:, None] * np.asarray(scales)[None, :]


def exact_film_rgb(m: ExportMaterial, angles_deg=ANGLES_DEG, scales=SCALES) -> np.ndarray:
    """bsdflab's exact film colour (A, S, 3), linear sRGB, over angle x thickness scale (a
    multilayer stack's layers all scaled together)."""
    from bsdflab.reference.approximations.study import SPECTRAL_GRID_NM, exact_rgb

    cos, s = _grid(angles_deg, scales)
    if m.stack:
        from bsdflab.optics import FilmLayer, FilmStack, film_reflectance
        from bsdflab.spectra import spectrum_to_rgb

        cols = []
        for k in scales:
            stack = FilmStack(m.ext_ior, [FilmLayer(n, d * k) for n, d in m.stack], m.int_ior)
            R = film_reflectance(stack, SPECTRAL_GRID_NM, cos_theta=np.cos(np.radians(angles_deg))[:, None])
            cols.append(spectrum_to_rgb(np.asarray(R), SPECTRAL_GRID_NM))
        return np.stack(cols, axis=1)
    n_film = m.film_ior if m.has_film else m.ext_ior
    return exact_rgb(m.ext_ior, n_film, m.int_ior, m.film_thickness_nm * s, cos)


def target_rgb(target: Target, thickness_nm: float, film_ior: float, base_ior: float,
               angles_deg=ANGLES_DEG, scales=SCALES) -> np.ndarray:
    """The target model's colour (A, S, 3) for its parameters, over the same grid."""
    cos, s = _grid(angles_deg, scales)
    return target.model(TARGET_OUTER_IOR, film_ior, base_ior, thickness_nm * s, cos)


def fit(m: ExportMaterial, target: Target, reference=None, angles_deg=ANGLES_DEG, scales=SCALES) -> FitResult:
    """Fit the target's (thickness, film index, base index) to ``reference`` (A, S, 3),
    by default the exact film of ``m``; starts from the material's own values."""
    from scipy.optimize import minimize

    from bsdflab.reference.approximations.study import rgb_to_lab

    ref = exact_film_rgb(m, angles_deg, scales) if reference is None else np.asarray(reference, float)
    ref_lab = rgb_to_lab(ref)

    def delta_e(rgb):
        import colour

        return colour.delta_E(rgb_to_lab(rgb), ref_lab, method="CIE 2000")

    def cost(x):
        x = target.clip(x)
        return float(np.mean(delta_e(target_rgb(target, *x, angles_deg, scales))))

    if not m.has_film:  # nothing to fit but the base index; the film is index-matched away
        x = target.clip(np.array([0.0, TARGET_OUTER_IOR, m.int_ior / m.ext_ior]))
        res = minimize(lambda b: cost([0.0, TARGET_OUTER_IOR, b[0]]), x[2:], method="Nelder-Mead",
                       options={"xatol": 1e-4, "fatol": 1e-4})
        best = target.clip(np.array([0.0, TARGET_OUTER_IOR, res.x[0]]))
    else:
        d0, n0, b0 = m.film_thickness_nm, m.film_ior, m.int_ior
        factors = np.linspace(0.85, 1.15, 13) if not m.stack else np.linspace(0.1, 1.5, 57)
        starts = [target.clip(np.array([d0 * f, n0 + dn, b0])) for f in factors for dn in (-0.15, 0.0, 0.15)]
        x0 = min(starts, key=cost)
        # a simplex a few per cent wide: the cost has many local minima in thickness
        simplex = np.vstack([x0, x0 + [0.02 * d0, 0, 0], x0 + [0, 0.03, 0], x0 + [0, 0, 0.03]])
        res = minimize(cost, x0, method="Nelder-Mead",
                       options={"xatol": 1e-3, "fatol": 1e-5, "maxiter": 600, "initial_simplex": simplex})
        best = target.clip(res.x) if res.fun <= cost(x0) else x0
    # what a file holds: 0.01 nm, indices to 1e-5 (MaterialX and USD write ~6 digits); the map is
    # computed for these rounded values, so the report describes the file
    best = np.array([round(float(best[0]), 2), round(float(best[1]), 5), round(float(best[2]), 5)])
    rgb = target_rgb(target, *best, angles_deg, scales)
    return FitResult(float(best[0]), float(best[1]), float(best[2]), np.asarray(angles_deg, float),
                     np.asarray(scales, float), ref, rgb, delta_e(rgb))
