"""Layered BSDFs estimated by Position-Free Monte Carlo, and their building blocks."""
from bsdflab.layered.slab import PhaseFunction, Slab
from bsdflab.layered.stack import Estimate, Layered

__all__ = ["Estimate", "Layered", "PhaseFunction", "Slab"]
