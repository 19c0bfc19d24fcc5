"""Synthetic structure-fit data made WITHOUT the fit's forward model: the stack's
reflectance by ``tmm`` (transfer matrices, pure Python), the instrument applied in numpy
(angle offset: tmm at theta + offset; bandwidth: a Gaussian slit as a dense trapezoid
convolution over a 0.25 nm grid; scale and background affine)."""
from __future__ import annotations

import numpy as np
import tmm

from bsdflab.fit.data import Dataset
from bsdflab.fit.materials import NAMED

FINE_STEP_NM = 0.25


def tmm_spectrum(n_of_wl, d_list, angle_deg, wavelengths):
    """Unpolarised R of the stack at each wavelength; n_of_wl(wl) -> list of media indices."""
    return np.array([tmm.unpolarized_RT(n_of_wl(w), [np.inf, *d_list, np.inf], np.radians(angle_deg), w)["R"]
                     for w in wavelengths])


def smeared(n_of_wl, d_list, angle_deg, wavelengths, fwhm):
    """The spectrum seen through a Gaussian slit of FWHM ``fwhm`` nm (dense convolution)."""
    if fwhm == 0:
        return tmm_spectrum(n_of_wl, d_list, angle_deg, wavelengths)
    s = fwhm / (2 * np.sqrt(2 * np.log(2)))
    fine = np.arange(wavelengths.min() - 6 * s, wavelengths.max() + 6 * s + FINE_STEP_NM, FINE_STEP_NM)
    r = tmm_spectrum(n_of_wl, d_list, angle_deg, fine)
    g = np.exp(-0.5 * ((fine[None, :] - wavelengths[:, None]) / s) ** 2)
    g[:, [0, -1]] *= 0.5                                   # trapezoid end weights
    return (g @ r) / g.sum(axis=1)


def two_layer_media(film_ior, substrate_ior):
    """air | film (n) | cytoplasm gap | keratin-like substrate (Cauchy A = substrate_ior, B 5890)."""
    air, gap = NAMED["air"], NAMED["cytoplasm"]
    return lambda w: [air.A, film_ior, gap.A, substrate_ior + 5890.0 / w**2]


def synthetic(truth: dict, angles, wavelengths, rel=0.01, absolute=0.002, seed=0):
    """A Dataset of the two-layer structure through the instrument in ``truth``."""
    media = two_layer_media(truth["film_ior"], truth["substrate_ior"])
    d = [truth["film_thickness_nm"], truth["gap_thickness_nm"]]
    y = np.concatenate([smeared(media, d, a + truth["angle_offset_deg"], wavelengths, truth["bandwidth_nm"])
                        for a in angles])
    y = truth["scale"] * y + truth["background"]
    sigma = np.sqrt(absolute**2 + (rel * y) ** 2)
    rng = np.random.default_rng(seed)
    n = len(y)
    return Dataset(np.zeros(n, int), np.repeat(np.asarray(angles, float), len(wavelengths)), np.full(n, np.nan),
                   np.tile(wavelengths, len(angles)), y + sigma * rng.standard_normal(n), sigma)


def two_layer_config(instrument: dict, walkers=24, max_steps=4000, seed=0, extra="") -> dict:
    """A structure-fit config (parsed TOML) for the two-layer structure above."""
    return {
        "structure": {"exterior": "air", "substrate": {"cauchy": [1.532, 5890.0]}, "layers": [
            {"name": "film", "material": {"n": 1.83}, "thickness_nm": 900.0},
            {"name": "gap", "material": "cytoplasm", "thickness_nm": 150.0}]},
        "instrument": instrument,
        "parameters": {"film_thickness_nm": {"prior": "uniform", "low": 820.0, "high": 980.0},
                       "gap_thickness_nm": {"prior": "uniform", "low": 80.0, "high": 250.0},
                       "film_ior": {"prior": "normal", "mean": 1.83, "sd": 0.05},
                       "substrate_ior": {"prior": "normal", "mean": 1.532, "sd": 0.03}},
        "sampler": {"walkers": walkers, "max_steps": max_steps, "tau_multiple": 30, "check_every": 200,
                    "seed": seed, "map_starts": 4},
    }


INSTRUMENT_PRIORS = {
    "scale": {"prior": "uniform", "low": 0.5, "high": 1.5},
    "background": {"prior": "normal", "mean": 0.0, "sd": 0.02},
    "angle_offset_deg": {"prior": "normal", "mean": 0.0, "sd": 2.0},
    "bandwidth_nm": {"prior": "uniform", "low": 0.0, "high": 40.0},
}
