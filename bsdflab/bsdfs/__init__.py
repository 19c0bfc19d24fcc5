"""BSDF models. Each file holds one model family; all share the interface in base.py."""
from .base import BSDF, BSDFSample, from_dict
from .conductor import Conductor
from .dielectric import Dielectric
from .diffuse import Diffuse
from .rough import RoughConductor, RoughDielectric

__all__ = ["BSDF", "BSDFSample", "Conductor", "Dielectric", "Diffuse", "RoughConductor",
           "RoughDielectric", "from_dict"]
