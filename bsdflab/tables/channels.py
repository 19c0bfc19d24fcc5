"""Which channels a table stores and how the model's channels project onto them."""
from __future__ import annotations

import numpy as np

from bsdflab.spectra import DEFAULT_WAVELENGTHS, srgb_weights
from bsdflab.util import args as check

RGB = ("R", "G", "B")
# Rec. 709 / sRGB luminance weights: the quantity whose error drives adaptive effort.
LUMINANCE_RGB = np.array([0.2126, 0.7152, 0.0722])


def table_channels(wavelengths) -> tuple[tuple[str, ...], np.ndarray, np.ndarray, np.ndarray]:
    """(channel names, model wavelengths, P (C x L), luminance weights (C,)).

    wavelengths None: store linear sRGB computed from the default spectral grid.
    Otherwise store those wavelengths (nm) and use their mean as the 'luminance'."""
    if wavelengths is None:
        W = srgb_weights(DEFAULT_WAVELENGTHS)
        return RGB, np.asarray(DEFAULT_WAVELENGTHS), W, LUMINANCE_RGB
    wl = check.real_array("wavelengths", wavelengths, 0.0, lo_open=True, ndim=1)
    names = tuple(f"{w:g}" for w in wl)
    if len(set(names)) != len(names):
        raise ValueError("wavelengths must be distinct")
    return names, wl, np.eye(len(wl)), np.full(len(wl), 1.0 / len(wl))


def channel_wavelengths(names: tuple[str, ...]) -> np.ndarray | None:
    """Wavelengths of a spectral table's channels; None for an RGB table."""
    if tuple(names) == RGB:
        return None
    return np.array([float(n) for n in names])
