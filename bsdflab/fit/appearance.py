"""The appearance posterior: what the parameter uncertainty means for colour.

For posterior draws and for the posterior-mean material, the forward model gives the
specular reflectance spectrum at each viewing angle (380-780 nm, 5 nm); colour-science's
CIE 1931 2° observer under D65 turns it into linear sRGB (bsdflab.spectra.srgb_weights),
XYZ and CIELAB (D65 white), and CIEDE2000 (``colour.delta_E``, "CIE 2000") measures each
draw's difference from the posterior-mean material, per angle.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bsdflab.fit.config import ModelSettings
from bsdflab.fit.data import GEOMETRIES, Dataset
from bsdflab.fit.forward import ForwardModel
from bsdflab.fit.parameters import ALL, ALL_NAMES, FORWARD_NAMES
from bsdflab.spectra import DEFAULT_WAVELENGTHS, srgb_weights
from bsdflab.spectra.colour_weights import rgb_colourspace

_FORWARD_COLS = [ALL_NAMES.index(n) for n in FORWARD_NAMES]


@dataclass
class AppearancePosterior:
    angles_deg: np.ndarray
    rgb: np.ndarray        # (draws, angles, 3) linear sRGB of the specular reflection
    rgb_mean: np.ndarray   # (angles, 3) of the posterior-mean material
    delta_e: np.ndarray    # (draws, angles) CIEDE2000 to the posterior-mean material

    def interval(self, level: float = 0.9) -> dict[str, np.ndarray]:
        """Per angle: median, central ``level`` interval and the ``level`` quantile (the
        "known to within Delta E00 <= x" bound)."""
        lo, hi = (1 - level) / 2, 1 - (1 - level) / 2
        q = np.quantile(self.delta_e, [0.5, lo, hi, level], axis=0)
        return {"median": q[0], "low": q[1], "high": q[2], "bound": q[3]}


def gloss_vectors(full: np.ndarray, model: ModelSettings) -> np.ndarray | None:
    """Parameter vectors whose smooth-model specular spectrum is the colour of ``model``'s
    gloss, or None (a platelet stack: the smooth model has one film). For the full model's
    rough top, the gloss at the mirror direction comes from facets along the normal, so its
    spectrum is the smooth film's specular reflectance times a grey factor (D G / 4 cos^2);
    the light scattered from below adds a little, which this leaves out. The spread is 0,
    no film is a film of thickness 0."""
    if model.kind == "smooth":
        return full
    if model.film == "stack":
        return None
    out = np.array(full, dtype=float, copy=True)
    for n in FORWARD_NAMES:
        col = ALL_NAMES.index(n)
        out[..., col] = np.where(np.isnan(out[..., col]), ALL[n].default, out[..., col])
    out[..., ALL_NAMES.index("film_thickness_spread_nm")] = 0.0
    if model.film == "none":
        out[..., ALL_NAMES.index("film_thickness_nm")] = 0.0
    return out


def specular_spectra(full: np.ndarray, angles_deg, thickness_nodes: int, angle_nodes: int) -> np.ndarray:
    """Specular reflectance (P, angles, wavelengths) for full parameter vectors (P, 11)."""
    wl = np.asarray(DEFAULT_WAVELENGTHS)
    a = np.asarray(angles_deg, float)
    grid_a, grid_w = np.meshgrid(a, wl, indexing="ij")
    n = grid_a.size
    ds = Dataset(np.full(n, GEOMETRIES.index("specular")), grid_a.ravel(), np.full(n, np.nan),
                 grid_w.ravel(), np.zeros(n), np.ones(n))
    model = ForwardModel(ds, thickness_nodes, angle_nodes)
    return model.evaluate(np.atleast_2d(full)[:, _FORWARD_COLS]).reshape(-1, len(a), len(wl))


def lab_of(rgb: np.ndarray) -> np.ndarray:
    import colour

    cs = rgb_colourspace()
    xyz = rgb @ np.asarray(cs.matrix_RGB_to_XYZ).T
    return colour.XYZ_to_Lab(xyz, illuminant=cs.whitepoint)


def appearance_posterior(draws_full: np.ndarray, mean_full: np.ndarray, angles_deg,
                         thickness_nodes: int, angle_nodes: int) -> AppearancePosterior:
    import colour

    spectra = specular_spectra(np.vstack([mean_full[None, :], draws_full]), angles_deg,
                               thickness_nodes, angle_nodes)
    rgb = spectra @ srgb_weights(DEFAULT_WAVELENGTHS).T
    lab = lab_of(rgb)
    de = colour.delta_E(lab[1:], lab[:1], method="CIE 2000")
    return AppearancePosterior(np.asarray(angles_deg, float), rgb[1:], rgb[0], de)
