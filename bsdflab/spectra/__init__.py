"""Spectral grids, spectral parameters and conversion of spectra to colour."""
from bsdflab.spectra.colour_weights import (
                             ColourSpace,
                             SensorModel,
                             rgb_to_spectrum,
                             sensor_model,
                             spectrum_to_rgb,
                             srgb_weights,
)
from bsdflab.spectra.grid import DEFAULT_STEP_NM, DEFAULT_WAVELENGTHS, wavelength_grid
from bsdflab.spectra.spectrum import Spectrum
from bsdflab.spectra.three_wavelength import THREE_WAVELENGTHS_NM, three_wavelength_rgb

__all__ = ["ColourSpace", "DEFAULT_STEP_NM", "SensorModel", "DEFAULT_WAVELENGTHS", "Spectrum",
           "THREE_WAVELENGTHS_NM", "rgb_to_spectrum", "sensor_model", "spectrum_to_rgb", "srgb_weights",
           "three_wavelength_rgb", "wavelength_grid"]
