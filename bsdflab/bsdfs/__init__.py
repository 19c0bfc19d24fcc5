"""BSDF models. Each file holds one model; all share the interface in base.py."""
from .base import BSDF, BSDFSample, from_dict
from .conductor import Conductor
from .dielectric import Dielectric
from .diffuse import Diffuse

__all__ = ["BSDF", "BSDFSample", "Conductor", "Dielectric", "Diffuse", "from_dict"]
