"""Layered BSDFs estimated by Position-Free Monte Carlo, and their building blocks."""
from .slab import PhaseFunction, Slab
from .stack import Estimate, Layered

__all__ = ["Estimate", "Layered", "PhaseFunction", "Slab"]
