"""Spectral grids, spectral parameters and conversion of spectra to colour."""
from .colour_weights import ColourSpace, rgb_to_spectrum, spectrum_to_rgb, srgb_weights
from .grid import DEFAULT_STEP_NM, DEFAULT_WAVELENGTHS, wavelength_grid
from .spectrum import Spectrum

__all__ = ["ColourSpace", "DEFAULT_STEP_NM", "DEFAULT_WAVELENGTHS", "Spectrum",
           "rgb_to_spectrum", "spectrum_to_rgb", "srgb_weights", "wavelength_grid"]
