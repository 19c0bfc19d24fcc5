"""How wrong are the thin-film approximations? CIEDE2000 maps against the exact spectral film.

For a single film (outer | film | base, real indices) each comparison model of this package
gives a linear sRGB reflectance; the reference is bsdflab's exact Airy reflectance
(`bsdflab.optics.film_reflectance`, unpolarised) on a 1 nm grid projected with bsdflab's
D65 -> linear sRGB weights (`bsdflab.spectra.srgb_weights`). Every colour then goes
linear sRGB -> XYZ -> CIELAB (D65 white, Y of a perfect reflector = 100) with
colour-science, and colour-science's CIEDE2000 gives the difference. Delta E00 = 2 is taken
as the just-noticeable difference (Sharma, Wu & Dalal 2005 put the JND near 1-2).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from bsdflab.reference.approximations import MODELS

JND = 2.0
SPECTRAL_GRID_NM = np.arange(380.0, 781.0, 1.0)


def exact_spectrum(n_outer, n_film, n_base, thickness_nm, cos_theta, wavelengths=SPECTRAL_GRID_NM):
    """Unpolarised exact reflectance (..., L) of the film (bsdflab.optics)."""
    from bsdflab.optics import film_reflectance

    d = np.asarray(thickness_nm, float)
    c = np.asarray(cos_theta, float)
    d, c = np.broadcast_arrays(d, c)
    R = film_reflectance((float(n_outer), float(n_film), 0.0, float(n_base)), wavelengths,
                         cos_theta=c[..., None], thickness_nm=d[..., None])
    return np.asarray(R)


def exact_rgb(n_outer, n_film, n_base, thickness_nm, cos_theta) -> np.ndarray:
    from bsdflab.spectra import spectrum_to_rgb

    return spectrum_to_rgb(exact_spectrum(n_outer, n_film, n_base, thickness_nm, cos_theta),
                           SPECTRAL_GRID_NM)


def exact_xyz_illuminant_e(n_outer, n_film, n_base, thickness_nm, cos_theta) -> np.ndarray:
    """CIE XYZ under the equal-energy illuminant (Y of a perfect reflector = 1) on 1 nm."""
    import colour

    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    cmf = np.stack([np.interp(SPECTRAL_GRID_NM, cmfs.wavelengths, cmfs.values[:, k]) for k in range(3)])
    R = exact_spectrum(n_outer, n_film, n_base, thickness_nm, cos_theta)
    return R @ cmf.T / cmf[1].sum()


def delta_e00_xyz_e(xyz_a, xyz_b) -> np.ndarray:
    """CIEDE2000 between XYZ colours under illuminant E (white (1, 1, 1))."""
    import colour

    white = np.array([1.0 / 3.0, 1.0 / 3.0])
    lab = [colour.XYZ_to_Lab(np.asarray(x, float), white) for x in (xyz_a, xyz_b)]
    return colour.delta_E(*lab, method="CIE 2000")


def rgb_to_lab(rgb) -> np.ndarray:
    """CIELAB (D65) of linear sRGB reflectances (..., 3)."""
    import colour

    from bsdflab.spectra.colour_weights import rgb_colourspace

    cs = rgb_colourspace()
    xyz = colour.RGB_to_XYZ(np.asarray(rgb, float), cs, apply_cctf_decoding=False)
    return colour.XYZ_to_Lab(xyz, cs.whitepoint)


def delta_e00(rgb_a, rgb_b) -> np.ndarray:
    import colour

    return colour.delta_E(rgb_to_lab(rgb_a), rgb_to_lab(rgb_b), method="CIE 2000")


@dataclass
class FilmStudy:
    """Delta E00 of every model against the exact film over an (angle x thickness) grid."""

    label: str
    indices: tuple[float, float, float]   # outer, film, base
    angles_deg: np.ndarray                # (A,)
    thicknesses_nm: np.ndarray            # (T,)
    exact: np.ndarray                     # (A, T, 3) linear sRGB
    models: dict[str, np.ndarray] = field(default_factory=dict)   # name -> (A, T, 3)
    delta_e: dict[str, np.ndarray] = field(default_factory=dict)  # name -> (A, T)

    def fraction_over(self, name: str, threshold: float = JND) -> float:
        return float(np.mean(self.delta_e[name] > threshold))

    def summary(self) -> dict[str, dict[str, float]]:
        return {name: {"fraction_over_jnd": self.fraction_over(name),
                       "median_delta_e00": float(np.median(e)), "max_delta_e00": float(e.max()),
                       "p95_delta_e00": float(np.percentile(e, 95))}
                for name, e in self.delta_e.items()}


def film_study(label, n_outer, n_film, n_base, angles_deg, thicknesses_nm, models=None) -> FilmStudy:
    """Run every model (default: all of ``MODELS``) over the grid angles x thicknesses."""
    a = np.asarray(angles_deg, float)
    t = np.asarray(thicknesses_nm, float)
    cos = np.cos(np.radians(a))[:, None] * np.ones_like(t)[None, :]
    d = np.ones_like(a)[:, None] * t[None, :]
    study = FilmStudy(label, (float(n_outer), float(n_film), float(n_base)), a, t,
                      exact_rgb(n_outer, n_film, n_base, d, cos))
    for name, fn in (models or MODELS).items():
        rgb = fn(n_outer, n_film, n_base, d, cos)
        study.models[name] = rgb
        study.delta_e[name] = delta_e00(rgb, study.exact)
    return study
