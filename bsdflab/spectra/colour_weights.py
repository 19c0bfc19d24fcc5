"""Spectrum <-> linear sRGB through colour-science's tables.

A reflectance-like spectrum v(lambda) on a grid becomes colour by
    XYZ = sum_l v(l) S(l) cmf(l) / sum_l S(l) ybar(l)
    RGB = M_XYZ->sRGB XYZ
with CIE 1931 2-degree colour-matching functions and illuminant S (D65 by default). The
3 x L matrix W mapping v to RGB is precomputed once per grid, so converting N spectra is
one matrix product. RGB inputs (e.g. a diffuse albedo given as a triple) are lifted to
spectra with Mallett & Yuksel's (2019) sRGB basis, which is linear in RGB and
reproduces sRGB reflectances under D65.

The illuminant's white computed on the grid is chromatically adapted (Bradford) to the
RGB space's white point, so a perfect white reflector is exactly (1, 1, 1).
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from bsdflab.spectra import colour_precomputed
from bsdflab.spectra.grid import DEFAULT_WAVELENGTHS
from bsdflab.util.args import real_array


@dataclass(frozen=True)
class ColourSpace:
    """Which observer, illuminant and RGB space spectra are projected to."""

    cmfs: str = "CIE 1931 2 Degree Standard Observer"
    illuminant: str = "D65"
    rgb: str = "sRGB"


@dataclass(frozen=True)
class SensorModel:
    """The parts of W on a grid: W = xyz_to_rgb @ (cmf * illuminant / sum(ybar * illuminant)).

    cmf (3, L) and illuminant (L,) are sampled at the grid (zero outside the tables);
    xyz_to_rgb (3, 3) is the RGB space's matrix after the Bradford adaptation of the grid's
    white. Mitsuba's spectral cross-check (reference/mitsuba_spectral.py) uses the parts."""

    cmf: np.ndarray
    illuminant: np.ndarray
    xyz_to_rgb: np.ndarray


@lru_cache(maxsize=32)
def _sensor(grid: tuple[float, ...], space: ColourSpace) -> SensorModel:
    if space == ColourSpace() and colour_precomputed.covers(grid):   # no colour import (its module says why)
        a = colour_precomputed.stored()
        return SensorModel(a["cmf"], a["illuminant"], a["xyz_to_rgb"])
    return compute_sensor(grid, space)


def compute_sensor(grid: tuple[float, ...], space: ColourSpace) -> SensorModel:
    """The sensor model on ``grid``, computed by colour-science."""
    import colour

    wl = np.asarray(grid)
    cmfs = colour.MSDS_CMFS[space.cmfs]
    illum = colour.SDS_ILLUMINANTS[space.illuminant]
    cmf = np.stack([np.interp(wl, cmfs.wavelengths, cmfs.values[:, k], left=0, right=0)
                    for k in range(3)])
    s = np.interp(wl, illum.wavelengths, illum.values, left=0, right=0)
    xyz_w = cmf * s / np.sum(cmf[1] * s)
    rgb_space = rgb_colourspace(space)
    # The illuminant's white as seen through these CMFs on this grid differs from the
    # RGB space's nominal white point by ~1e-4; adapt it (Bradford) so that a perfect
    # reflector maps to RGB (1, 1, 1) exactly, as colour.XYZ_to_RGB would with that white.
    white = xyz_w.sum(axis=1)
    target = colour.xy_to_XYZ(rgb_space.whitepoint)
    cat = colour.adaptation.matrix_chromatic_adaptation_VonKries(white, target, transform="Bradford")
    parts = SensorModel(cmf, s, rgb_space.matrix_XYZ_to_RGB @ cat)
    for a in (parts.cmf, parts.illuminant, parts.xyz_to_rgb):
        a.setflags(write=False)
    return parts


@lru_cache(maxsize=32)
def _weights(grid: tuple[float, ...], space: ColourSpace) -> np.ndarray:
    p = _sensor(grid, space)
    W = p.xyz_to_rgb @ (p.cmf * p.illuminant / np.sum(p.cmf[1] * p.illuminant))
    W.setflags(write=False)
    return W


def sensor_model(wavelengths, space: ColourSpace = ColourSpace()) -> SensorModel:
    """The CMFs, illuminant and XYZ -> RGB matrix that make up ``srgb_weights``."""
    wl = real_array("wavelengths", wavelengths, 0.0, lo_open=True, ndim=1)
    return _sensor(tuple(float(x) for x in wl), space)


def rgb_colourspace(space: ColourSpace = ColourSpace()):
    """colour-science's RGB colourspace with matrices derived from its primaries and white
    point (not the 4-decimal rounded IEC sRGB matrix, which maps white to 1 +- 2e-4)."""
    import colour

    cs = colour.RGB_COLOURSPACES[space.rgb].copy()
    cs.use_derived_transformation_matrices(True)
    return cs


def srgb_weights(wavelengths, space: ColourSpace = ColourSpace()) -> np.ndarray:
    """The (3, L) matrix taking a spectrum sampled at `wavelengths` (nm) to linear RGB."""
    wl = real_array("wavelengths", wavelengths, 0.0, lo_open=True, ndim=1)
    return _weights(tuple(float(x) for x in wl), space)


def spectrum_to_rgb(values, wavelengths, space: ColourSpace = ColourSpace()) -> np.ndarray:
    """Linear RGB of spectra `values` (..., L) sampled at `wavelengths` (L,)."""
    W = srgb_weights(wavelengths, space)
    v = np.asarray(values, dtype=np.float64)
    if v.shape[-1] != W.shape[1]:
        raise ValueError(f"values must end in an axis of {W.shape[1]} wavelengths, got shape {v.shape}")
    return v @ W.T


@lru_cache(maxsize=32)
def _basis(grid: tuple[float, ...]) -> np.ndarray:
    if colour_precomputed.covers(grid):
        return colour_precomputed.stored()["basis"]
    return compute_basis(grid)


def compute_basis(grid: tuple[float, ...]) -> np.ndarray:
    """Mallett & Yuksel's sRGB basis on ``grid``, from colour-science's table."""
    import colour

    basis = colour.recovery.MSDS_BASIS_FUNCTIONS_sRGB_MALLETT2019
    wl = np.asarray(grid)
    B = np.stack([np.interp(wl, basis.wavelengths, basis.values[:, k]) for k in range(3)])
    B.setflags(write=False)
    return B


def rgb_to_spectrum(rgb, wavelengths) -> np.ndarray:
    """Spectra (..., L) for linear sRGB triples (..., 3) in [0, 1] (Mallett-Yuksel 2019)."""
    c = np.asarray(rgb, dtype=np.float64)
    if c.shape[-1] != 3:
        raise ValueError(f"rgb must end in an axis of 3, got shape {c.shape}")
    wl = real_array("wavelengths", wavelengths, 0.0, lo_open=True, ndim=1)
    return c @ _basis(tuple(float(x) for x in wl))


def precomputed_arrays() -> dict[str, np.ndarray]:
    """What bsdflab/spectra/colour_default_grid.npz must hold: the default grid's sensor
    model and basis, computed by colour-science now."""
    grid = tuple(float(x) for x in DEFAULT_WAVELENGTHS)
    sensor = compute_sensor(grid, ColourSpace())
    return {"wavelengths": np.asarray(grid), "cmf": sensor.cmf, "illuminant": sensor.illuminant,
            "xyz_to_rgb": sensor.xyz_to_rgb, "basis": compute_basis(grid)}


def store_precomputed() -> None:
    """Regenerate the stored arrays from colour-science (after an upgrade)."""
    colour_precomputed.write(precomputed_arrays())
