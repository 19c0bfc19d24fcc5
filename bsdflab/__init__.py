"""bsdflab: measure, tabulate, render and validate layered thin-film BSDFs.

Quick use::

    import numpy as np, bsdflab as bl
    bsdf = bl.Conductor(material="Au")
    s = bsdf.sample(np.array([[0.0, 0.6, 0.8]]))
    rgb = bl.Diffuse(0.5).eval([0, 0, 1], [0, 0.6, 0.8])      # (1, 3) linear sRGB
"""
from bsdflab import optics, presets, spectra
from bsdflab._version import __version__
from bsdflab.bsdfs import BSDF, BSDFSample, Conductor, Dielectric, Diffuse, RoughConductor, RoughDielectric, from_dict
from bsdflab.layered import Layered, PhaseFunction, Slab
from bsdflab.lobes import Lobe
from bsdflab.measured import Measured, Merl
from bsdflab.spectra import DEFAULT_WAVELENGTHS, Spectrum, spectrum_to_rgb

__all__ = ["BSDF", "BSDFSample", "Conductor", "DEFAULT_WAVELENGTHS", "Dielectric", "Diffuse",
           "Layered", "Lobe", "Measured", "Merl", "PhaseFunction", "RoughConductor", "Slab", "RoughDielectric",
           "Spectrum", "from_dict", "optics", "presets", "spectra", "spectrum_to_rgb", "__version__"]
