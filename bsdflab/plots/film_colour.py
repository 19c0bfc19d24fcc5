"""The colour a thin film or stack reflects, spectrally and the three-wavelength way.

Everything is one vectorised call of `bsdflab.optics.film_reflectance` over
(thickness, angle, wavelength); no Python loop touches pixels or wavelengths.

Sweeping thickness
------------------
For one film (the tuple ``(n0, n1, d, n2)``) the thickness axis is the film's thickness,
passed as `thickness_nm`. A `FilmStack`'s layers are scalars, so its axis is the total
stack thickness with every layer scaled by the same factor s, computed through the exact
identity R(lambda; s d) = R(lambda / s; d): the phase 2 pi n d cos(theta) / lambda depends
on d / lambda only, and the interface coefficients not at all when every index is
constant (which is all the CLI builds; others raise ValueError).
"""
from __future__ import annotations

import numpy as np

from bsdflab.optics import Constant, FilmStack, film_reflectance
from bsdflab.optics.dispersion import as_dispersion
from bsdflab.spectra import (
    DEFAULT_STEP_NM,
    THREE_WAVELENGTHS_NM,
    spectrum_to_rgb,
    three_wavelength_rgb,
    wavelength_grid,
)
from bsdflab.spectra.grid import DEFAULT_RANGE_NM

# Thicker films than this (optical thickness n d summed over layers, nm) need wavelength
# grids so fine that the image no longer fits comfortably in memory; they look white.
MAX_OPTICAL_THICKNESS_NM = 10_000.0
# Samples per shortest fringe period of the reflectance in wavelength (Nyquist needs 2).
SAMPLES_PER_FRINGE = 6
# Zero thickness in the stack's wavelength scaling: lambda / s stays finite.
_TINY_SCALE = 1e-9
# display_exposure's default largest incidence angle (radians).
_THETA_MAX_DEFAULT = np.radians(60.0)


def optical_thickness_nm(film, thickness_nm=None) -> float:
    """The largest sum of n d over the film's layers (nm), n at its largest in 380-780 nm.

    Parameters
    ----------
    film : FilmStack or tuple (n0, n1, d_nm, n2)
        The film.
    thickness_nm : array_like, optional
        A thickness sweep as in `reflectance`; its largest value counts.
    """
    if isinstance(film, FilmStack):
        n_d = sum(np.max(layer.material.index(np.asarray(DEFAULT_RANGE_NM)).real)
                  * layer.thickness_nm for layer in film.layers)
        scale = 1.0 if thickness_nm is None else float(np.max(thickness_nm)) / _total(film)
        return float(n_d * scale)
    _, n1, d, _ = film
    n = np.max(as_dispersion(n1, "n1").index(np.asarray(DEFAULT_RANGE_NM)).real)
    return float(n * np.max(d if thickness_nm is None else thickness_nm))


def _total(stack: FilmStack) -> float:
    """A stack's total thickness in nm, which a thickness sweep scales."""
    total = sum(layer.thickness_nm for layer in stack.layers)
    if total <= 0:
        raise ValueError("sweeping a stack's thickness needs layers of nonzero total thickness")
    return total


def colour_wavelengths(max_optical_thickness_nm: float) -> np.ndarray:
    """A 380-780 nm grid that resolves every fringe of films up to this optical thickness.

    Parameters
    ----------
    max_optical_thickness_nm : float
        Largest sum of n d (nm) the grid must serve.

    Returns
    -------
    ndarray
        Wavelengths in nm: the default 5 nm grid, or finer so that the shortest fringe
        period lambda_min^2 / (2 n d) holds `SAMPLES_PER_FRINGE` samples.
    """
    if max_optical_thickness_nm > MAX_OPTICAL_THICKNESS_NM:
        raise ValueError(f"the optical thickness n*d reaches {max_optical_thickness_nm:.0f} nm, "
                         f"above the {MAX_OPTICAL_THICKNESS_NM:.0f} nm this figure resolves "
                         "(such films reflect nearly white); reduce --thickness-range "
                         "(or the film's index or thickness)")
    start, end = DEFAULT_RANGE_NM
    period = start**2 / (2.0 * max(max_optical_thickness_nm, 1e-9))
    step = min(DEFAULT_STEP_NM, period / SAMPLES_PER_FRINGE)
    return wavelength_grid(start, end, (end - start) / np.ceil((end - start) / step))


def reflectance(film, wavelength_nm, theta, thickness_nm=None) -> np.ndarray:
    """Unpolarised reflectance, broadcast over wavelength, angle and thickness.

    Parameters
    ----------
    film : FilmStack or tuple (n0, n1, d_nm, n2)
        The film, with constant indices if it is a stack and `thickness_nm` is given.
    wavelength_nm, theta : array_like
        Vacuum wavelengths in nm and angles of incidence in radians.
    thickness_nm : array_like, optional
        The film's thickness in nm, or a stack's total thickness (all layers scaled
        together); None keeps the film's own.

    Returns
    -------
    ndarray
        R in [0, 1], of the broadcast shape.
    """
    if thickness_nm is None:
        return film_reflectance(film, wavelength_nm, theta)
    if not isinstance(film, FilmStack):
        return film_reflectance(film, wavelength_nm, theta, thickness_nm=thickness_nm)
    media = [film.incident, film.substrate, *(layer.material for layer in film.layers)]
    if not all(isinstance(m, Constant) for m in media):
        raise ValueError("sweeping a stack's thickness needs constant indices")
    scale = np.maximum(np.asarray(thickness_nm, dtype=float) / _total(film), _TINY_SCALE)
    return film_reflectance(film, np.asarray(wavelength_nm) / scale, theta)


def spectral_rgb(film, theta, thickness_nm=None, wavelengths=None) -> np.ndarray:
    """Linear sRGB (D65) of the reflected spectrum: bsdflab's colour.

    Parameters
    ----------
    film, theta, thickness_nm
        As for `reflectance`; theta and thickness_nm broadcast against each other.
    wavelengths : array_like, optional
        The grid to integrate on (nm); default `colour_wavelengths` for this film.

    Returns
    -------
    ndarray, shape (..., 3)
        Linear sRGB; a perfect white reflector is (1, 1, 1).
    """
    if wavelengths is None:
        wavelengths = colour_wavelengths(optical_thickness_nm(film, thickness_nm))
    wl = np.asarray(wavelengths, dtype=float)
    r = reflectance(film, wl, np.asarray(theta)[..., None],
                    None if thickness_nm is None else np.asarray(thickness_nm)[..., None])
    return spectrum_to_rgb(r, wl)


def three_wavelength_colour(film, theta, thickness_nm=None) -> np.ndarray:
    """The three-wavelength "RGB" (`bsdflab.spectra.three_wavelength`): reflectance at 650, 510
    and 475 nm, shape (..., 3)."""
    wl = np.asarray(THREE_WAVELENGTHS_NM)
    r = reflectance(film, wl, np.asarray(theta)[..., None],
                    None if thickness_nm is None else np.asarray(thickness_nm)[..., None])
    return three_wavelength_rgb(r)


def delta_e_2000(rgb_a, rgb_b) -> np.ndarray:
    """CIEDE2000 colour difference of two linear-sRGB colours (D65, white = 1).

    About 1-2 is just noticeable; above ~10 two swatches look clearly different.
    """
    import colour

    def lab(rgb):
        return colour.XYZ_to_Lab(colour.RGB_to_XYZ(np.asarray(rgb, dtype=float), "sRGB"))

    return colour.delta_E(lab(rgb_a), lab(rgb_b), method="CIE 2000")


def display_exposure(rgb, theta, theta_max=_THETA_MAX_DEFAULT, percentile=99.0) -> float:
    """A display gain k >= 1: the given percentile of max(R, G, B) at theta <= theta_max -> 1.

    Grazing angles (R -> 1) are left out so that they do not darken the film's colours;
    k is never below 1, so a perfect white reflector never shows darker than white.
    """
    peak = np.max(np.asarray(rgb)[np.broadcast_to(np.asarray(theta) <= theta_max,
                                                 np.shape(rgb)[:-1])], axis=-1)
    level = np.percentile(peak, percentile) if peak.size else 1.0
    return 1.0 / min(max(float(level), 1e-6), 1.0)


def display_srgb(rgb, exposure: float) -> np.ndarray:
    """Linear sRGB -> encoded sRGB in [0, 1] for display.

    Multiplies by `exposure`, clips out-of-gamut negative channels to 0, divides a pixel
    whose brightest channel exceeds 1 by that channel (keeping its hue, unlike per-channel
    clipping), then applies the sRGB transfer curve.
    """
    import colour

    c = np.clip(np.asarray(rgb, dtype=float) * exposure, 0.0, None)
    c = c / np.maximum(1.0, c.max(axis=-1, keepdims=True))
    return np.clip(colour.cctf_encoding(c, function="sRGB"), 0.0, 1.0)


def film_thickness_nm(film) -> float:
    """The film's own thickness, or a stack's total thickness, in nm."""
    if isinstance(film, FilmStack):
        return float(sum(layer.thickness_nm for layer in film.layers))
    return float(np.max(film[2]))
