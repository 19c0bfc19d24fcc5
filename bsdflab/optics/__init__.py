"""Optics: Fresnel coefficients, named metals, thin films."""
from .fresnel import fresnel_amplitudes, fresnel_reflectance, fresnel_transmittance
from .metals import METALS, metal_ior

__all__ = ["METALS", "fresnel_amplitudes", "fresnel_reflectance", "fresnel_transmittance",
           "metal_ior"]
