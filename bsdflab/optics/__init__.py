"""Optics: Fresnel coefficients, named metals, thin films."""
from bsdflab.optics.dispersion import Cauchy, Constant, Dispersion, Tabulated, dispersion_from_dict
from bsdflab.optics.fresnel import fresnel_amplitudes, fresnel_reflectance, fresnel_transmittance
from bsdflab.optics.metals import METALS, metal_ior
from bsdflab.optics.thin_film import (
                        FilmAmplitudes,
                        FilmLayer,
                        FilmStack,
                        film_amplitudes,
                        film_reflectance,
                        film_transmittance,
)
from bsdflab.util.deprecation import renamed_attributes

__all__ = ["METALS", "fresnel_amplitudes", "fresnel_reflectance", "fresnel_transmittance",
           "metal_ior",
           "Cauchy", "Constant", "Dispersion", "Tabulated", "dispersion_from_dict",
           "FilmAmplitudes", "FilmLayer", "FilmStack", "film_amplitudes", "film_reflectance",
           "film_transmittance"]

# Old names (issue 34), served with a FutureWarning.
__getattr__ = renamed_attributes(__name__, {"Layer": ("FilmLayer", FilmLayer)})
