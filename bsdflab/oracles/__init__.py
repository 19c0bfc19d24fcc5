"""Deterministic reference models ("oracles") for validating bsdflab's stochastic BSDFs.

Each oracle evaluates a configuration exactly (to quadrature precision) with optics that
are independent of the code it checks (the ``tmm`` package, not bsdflab's C++ core).
``microsurface`` is the stochastic exception: Heitz et al. 2016's random walk on a Smith
microsurface (numpy), the reference for rough interfaces' multiple scattering.
"""
from .coated_diffuse import CoatedDiffuseOracle

__all__ = ["CoatedDiffuseOracle"]
