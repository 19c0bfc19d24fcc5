"""Optics: Fresnel coefficients, named metals, thin films."""
from bsdflab.optics.dispersion import Cauchy, Constant, Dispersion, Tabulated, dispersion_from_dict
from bsdflab.optics.fresnel import fresnel_amplitudes, fresnel_reflectance, fresnel_transmittance
from bsdflab.optics.metals import METALS, metal_ior
from bsdflab.optics.thin_film import (
                        FilmAmplitudes,
                        FilmStack,
                        Layer,
                        film_amplitudes,
                        film_reflectance,
                        film_transmittance,
)

__all__ = ["METALS", "fresnel_amplitudes", "fresnel_reflectance", "fresnel_transmittance",
           "metal_ior",
           "Cauchy", "Constant", "Dispersion", "Tabulated", "dispersion_from_dict",
           "FilmAmplitudes", "FilmStack", "Layer", "film_amplitudes", "film_reflectance",
           "film_transmittance"]
