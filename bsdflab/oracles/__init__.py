"""Deterministic reference models ("oracles") for validating bsdflab's stochastic BSDFs.

Each oracle evaluates a configuration exactly (to quadrature precision) with optics that
are independent of the code it checks (the ``tmm`` package or the oracle's own closed
forms, never bsdflab's C++ core). ``CoatedDiffuseOracle``: non-scattering slabs, thin
films; ``AddingDoublingOracle``: scattering slabs (isotropic, Henyey-Greenstein).
``microsurface`` is the stochastic exception: Heitz et al. 2016's random walk on a Smith
microsurface (numpy), the reference for rough interfaces' multiple scattering.
"""
from bsdflab.oracles.coated_diffuse import CoatedDiffuseOracle
from bsdflab.oracles.slab_adding_doubling import AddingDoublingOracle

__all__ = ["AddingDoublingOracle", "CoatedDiffuseOracle"]
