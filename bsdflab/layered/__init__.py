"""Layered BSDFs estimated by Position-Free Monte Carlo, and their building blocks."""
from .slab import PhaseFunction, Slab
from .stack import Layered

__all__ = ["Layered", "PhaseFunction", "Slab"]
