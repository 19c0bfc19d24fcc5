"""Our spectral scene for Mitsuba 3's spectral variants: explicit spectra, one sensor.

``render(..., spectral=True)`` (docs/spectral_rendering.md) carries the 81 bins of the
default grid G = 380, 385, ..., 780 nm and makes a pixel of a path's spectrum v by

    ours = Σ_l W[:, l] v_l,   W = A · cmf(λ_l) S(λ_l) / Σ_k S(λ_k) ȳ(λ_k)

(S = D65, A = XYZ -> linear sRGB after a Bradford adaptation; ``srgb_weights``). Spectra
are reflectance-like: an emitter of RGB e emits v = U e (Mallett-Yuksel lift U) and the
illuminant lives in W. A 5 nm-binned renderer's spectrum *is* a step function: bin l
stands for the band B_l = [λ_l - 2.5, λ_l + 2.5] nm. So the same scene for Mitsuba is:

  * every spectrum as that step function, an ``irregular`` spectrum whose value is v_l
    on B_l (``step_spectrum_dict``; the steps are ramps 2 EDGE_NM wide centred on the
    band edges, whose integral equals the sharp step's): emitters (area lights, a constant
    environment) emit U e and are zero outside 377.5-782.5 nm; BSDF parameters are the
    81-bin spectra our renderer uses (``bsdf_spectra``: ``Spectrum.at(G)``, i.e. RGB
    parameters lifted by U, tabulated data such as a named metal's complex index
    interpolated to G, (η, k) / ext_ior for conductors as in the RGB converter), held
    constant outside. Mitsuba never applies its Jakob-Hanika uplift or its D65;
  * the sensor is W as a step function too: ``render_mitsuba(spectral=True)`` scores each
    sample as W[:, l(λ)] L(λ) / (Δλ p(λ)) in its moments integrator (mitsuba_render.py),
    λ drawn by Mitsuba's sensor with density p (``pdf_rgb_spectrum``, 360-830 nm). Its
    expectation is Σ_l W[:, l] (1/Δλ) ∫_{B_l} L = Σ_l W[:, l] v_l: our pixel, exactly.

``residual`` measures what is left (the ramps' products, ~1e-6), and, for comparison,
the residual of the obvious alternative (linear spectra L = K S U e through Mitsuba's own
CIE film and A): up to 1e-2 relative on multi-bounce coloured paths (docs).

Not convertible, with the reason (``ValueError``): lat-long environments ("sky",
"envmap": our per-texel spectra are lifts of each texel's RGB, while Mitsuba's ``envmap``
uplifts RGB texels by Jakob-Hanika times D65 and takes no per-texel spectrum); RGB tables
and the bsdflab plugin (they answer in RGB; a spectral Mitsuba path would need the answer
at its own wavelengths); models without a Mitsuba counterpart (thin films, layered,
multiscatter), as in RGB.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from bsdflab.reference.mitsuba_bsdf import _bsdf_dict, to_mitsuba
from bsdflab.spectra import DEFAULT_STEP_NM, DEFAULT_WAVELENGTHS, Spectrum, rgb_to_spectrum, sensor_model, srgb_weights

GRID = DEFAULT_WAVELENGTHS
STEP_NM = DEFAULT_STEP_NM
EDGES = np.concatenate([GRID - 0.5 * STEP_NM, [GRID[-1] + 0.5 * STEP_NM]])  # band edges, 82
# Half-width of the ramp at each band edge: well above float32's resolution of a
# wavelength (6e-5 nm at 500 nm), far below the band.
EDGE_NM = 0.01
# Mitsuba's CIE tables and wavelength sampling cover 360-830 nm.
MITSUBA_RANGE_NM = (360.0, 830.0)
# MI_CIE_Y_NORMALIZATION of Mitsuba 3.9 (mitsuba/core/spectrum.h): 1 / ∫ ȳ over its table.
MITSUBA_Y_NORMALIZATION = 1.0 / 106.7502593994140625
# Any wavelength inside the grid: the RGB converter's structure (lobes, rough parameters,
# two-sidedness, exclusions) is taken at it and the spectral parameters replaced.
_STRUCTURE_NM = 550.0


def _text(values) -> str:
    return ", ".join(repr(float(x)) for x in np.asarray(values, dtype=np.float64))


def step_nodes(values, outside: str) -> tuple[np.ndarray, np.ndarray]:
    """(wavelengths, values) of the piecewise-linear function that is ``values[l]`` on band
    l (ramps of half-width EDGE_NM at the edges); outside the bands 'zero' or 'hold'."""
    v = np.asarray(values, dtype=np.float64)
    if v.shape != GRID.shape:
        raise ValueError(f"a spectrum on the grid needs {len(GRID)} values, got shape {v.shape}")
    wl = np.stack([EDGES[:-1] + EDGE_NM, EDGES[1:] - EDGE_NM], axis=1).ravel()
    vals = np.repeat(v, 2)
    if outside == "zero":
        return (np.concatenate([[EDGES[0] - EDGE_NM], wl, [EDGES[-1] + EDGE_NM]]),
                np.concatenate([[0.0], vals, [0.0]]))
    if outside == "hold":
        return (np.concatenate([[MITSUBA_RANGE_NM[0]], wl, [MITSUBA_RANGE_NM[1]]]),
                np.concatenate([v[:1], vals, v[-1:]]))
    raise ValueError(f"outside must be 'zero' or 'hold', got {outside!r}")


def step_spectrum_dict(values, outside: str) -> dict[str, Any] | float:
    """Mitsuba's ``irregular`` spectrum of ``step_nodes``; a plain float where that is the
    same function (zero, or constant and held), since Mitsuba refuses an all-zero one."""
    wl, v = step_nodes(values, outside)
    if not np.any(v) or (outside == "hold" and np.all(v == v[0])):
        return float(v[0])
    return {"type": "irregular", "wavelengths": _text(wl), "values": _text(v)}


def lifted(rgb) -> np.ndarray:
    """U e: the spectrum our renderer gives RGB emission (RenderScene::lift)."""
    return rgb_to_spectrum(np.asarray(rgb, dtype=np.float64), GRID)


def emission(rgb) -> dict[str, Any]:
    """Mitsuba's radiance for an RGB emission or constant environment of ours."""
    return step_spectrum_dict(lifted(rgb), "zero")


def sensor_bins() -> np.ndarray:
    """(3, 81) W / Δλ: the sensor's response per nm in each band (moments integrator)."""
    return np.asarray(srgb_weights(GRID)) / STEP_NM


def bsdf_spectra(bsdf) -> dict[str, np.ndarray]:
    """The 81-bin spectra our renderer uses for ``bsdf``'s spectral parameters, by the name
    of Mitsuba's parameter (conductors: relative to ext_ior, as Mitsuba takes them)."""
    from bsdflab.optics.metals import metal_ior

    d = _bsdf_dict(bsdf)
    kind = d["type"]
    if kind == "diffuse":
        return {"reflectance": Spectrum.from_dict(d["reflectance"]).at(GRID)}
    if kind in ("conductor", "roughconductor") and ("material" in d or "eta" in d):
        eta, k = metal_ior(d["material"]) if "material" in d else (
            Spectrum.from_dict(d["eta"]), Spectrum.from_dict(d["k"]))
        return {"eta": eta.at(GRID) / d["ext_ior"], "k": k.at(GRID) / d["ext_ior"]}
    return {}


def to_mitsuba_spectral(bsdf) -> dict[str, Any]:
    """The plugin dict of a bsdflab BSDF for a Mitsuba spectral variant: ``to_mitsuba``'s
    structure with every spectral parameter as an explicit step spectrum (bsdf_spectra)."""
    d = _bsdf_dict(bsdf)
    plugin = to_mitsuba(d, wavelength=_STRUCTURE_NM)  # raises for models without a counterpart
    inner = plugin["bsdf"] if plugin["type"] == "twosided" else plugin
    for name, values in bsdf_spectra(d).items():
        inner[name] = step_spectrum_dict(values, "hold")
    return plugin


def environment(env) -> dict[str, Any] | None:
    """Mitsuba's emitter for our environment in spectral mode (None for 'none')."""
    if env.type == "none":
        return None
    if env.type == "constant":
        return {"type": "constant", "radiance": emission(env.radiance)}
    raise ValueError(f"a {env.type!r} environment has no spectral Mitsuba counterpart: our spectral mode "
                     "lifts each texel's RGB (Mallett-Yuksel), while Mitsuba's envmap uplifts RGB texels "
                     "by Jakob-Hanika times D65 and takes no per-texel spectrum; use a constant environment")


# -- what is left of the difference -------------------------------------------------------
def residual(spectra, emission_rgb, mapping: str = "bins", fine_step_nm: float = 1e-3) -> float:
    """Largest relative difference, over RGB channels, between our pixel value and the
    value Mitsuba's estimator converges to, for a path whose spectrum is ``U emission_rgb``
    times the product of ``spectra`` (each (81,) on the grid: a reflectance seen once,
    twice, ...). Integrals on a ``fine_step_nm`` grid (exact to ~1e-8 here).

    mapping 'bins': this module's step spectra and step sensor. 'continuous', for
    comparison: spectra as the linear interpolants of the node values, the emitter as
    K S U e with K = 1 / (MI_CIE_Y_NORMALIZATION Δλ Σ S ȳ), Mitsuba's CIE film (its CMF
    table equals colour-science's at the nodes to 6e-8) and the matrix A.
    """
    factors = [np.asarray(f, dtype=np.float64) for f in spectra]
    e = lifted(emission_rgb)
    ours = srgb_weights(GRID) @ (np.prod(factors, axis=0) * e if factors else e)
    fine = np.arange(MITSUBA_RANGE_NM[0], MITSUBA_RANGE_NM[1] + 0.5 * fine_step_nm, fine_step_nm)
    if mapping == "bins":
        curves = [np.interp(fine, *step_nodes(e, "zero"), left=0, right=0)]
        curves += [np.interp(fine, *step_nodes(f, "hold")) for f in factors]
        band = np.clip(np.searchsorted(EDGES, fine, side="right") - 1, 0, len(GRID) - 1)
        inside = (fine >= EDGES[0]) & (fine < EDGES[-1])
        sensor = np.where(inside, sensor_bins()[:, band], 0.0)
        theirs = np.trapezoid(sensor * np.prod(curves, axis=0), fine, axis=1)
    elif mapping == "continuous":
        p = sensor_model(GRID)
        k = 1.0 / (MITSUBA_Y_NORMALIZATION * STEP_NM * np.sum(p.illuminant * p.cmf[1]))
        curves = [np.interp(fine, GRID, f, left=0, right=0) for f in [k * p.illuminant * e, *factors]]
        cmf = np.stack([np.interp(fine, GRID, p.cmf[c], left=0, right=0) for c in range(3)])
        theirs = p.xyz_to_rgb @ (MITSUBA_Y_NORMALIZATION * np.trapezoid(cmf * np.prod(curves, axis=0), fine, axis=1))
    else:
        raise ValueError(f"mapping must be 'bins' or 'continuous', got {mapping!r}")
    return float(np.max(np.abs(theirs - ours) / np.maximum(np.abs(ours), 1e-12)))
