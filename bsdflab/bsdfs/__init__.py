"""BSDF models. Each file holds one model family; all share the interface in base.py."""
from bsdflab.bsdfs.base import BSDF, BSDFSample, from_dict
from bsdflab.bsdfs.conductor import Conductor
from bsdflab.bsdfs.dielectric import Dielectric
from bsdflab.bsdfs.diffuse import Diffuse
from bsdflab.bsdfs.rough import RoughConductor, RoughDielectric

__all__ = ["BSDF", "BSDFSample", "Conductor", "Dielectric", "Diffuse", "RoughConductor",
           "RoughDielectric", "from_dict"]
