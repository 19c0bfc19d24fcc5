"""Deterministic solvers for layered BSDFs (docs/solvers.md)."""
from bsdflab.solvers.adding_doubling import Solution, solve

__all__ = ["Solution", "solve"]
