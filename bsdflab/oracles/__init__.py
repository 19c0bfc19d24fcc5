"""Deterministic reference models ("oracles") for validating bsdflab's stochastic BSDFs.

Each oracle evaluates a configuration exactly (to quadrature precision) with optics that
are independent of the code it checks (the ``tmm`` package or the oracle's own closed
forms, never bsdflab's C++ core). ``CoatedDiffuseOracle``: non-scattering slabs, thin
films; ``AddingDoublingOracle``: scattering slabs (isotropic, Henyey-Greenstein).
"""
from .adding_doubling import AddingDoublingOracle
from .coated_diffuse import CoatedDiffuseOracle

__all__ = ["AddingDoublingOracle", "CoatedDiffuseOracle"]
