"""Statistical tests for BSDF implementations: use them on bsdflab's models or your own.

A BSDF here is any object with bsdflab's vectorised interface (see
``bsdflab.bsdfs.base``): ``eval(wi, wo, wavelengths=None, lobes=...)`` returning
f |cos theta_o| per channel, ``pdf(wi, wo, lobes=...)`` and
``sample(wi, *, seed=..., wavelengths=None, lobes=...)`` returning a ``BSDFSample``.
Directions use the local frame, +z the normal, both pointing away from the surface.

What each tool checks
---------------------
``bsdf_chi2`` / ``ChiSquareTest`` (chi2.py)
    ``sample`` draws directions with the density ``pdf`` claims (Pearson chi-square
    test over a grid on the whole sphere, as in Mitsuba 3).
``discrete_choice_chi2`` (discrete.py)
    Discrete outcomes, such as the lobe a delta BSDF picks, occur with the expected
    probabilities (exact binomial test for two outcomes, chi-square for more).
``albedo_uniform`` / ``albedo_sampled`` (furnace.py)
    White furnace: the integral of f |cos| by uniform sampling of ``eval`` and by the
    mean ``sample`` weight; they must agree, and be <= 1 (= 1 without absorption).
``reciprocity_error`` / ``eval_pdf_consistency`` (checks.py)
    f(wi, wo) = f(wo, wi); ``sample``'s weight and pdf equal ``eval / pdf`` and ``pdf``.
``pearson_chi2``, ``pool_low_expected``, ``sidak_significance``, ``sidak_z_limit`` (stats.py)
    The statistical pieces, for tests of your own.

Significance and repeated tests
-------------------------------
A statistical test rejects a *correct* sampler with probability ``significance``.
When you run many tests (several BSDFs, several incident angles), pass their number
as ``test_count``: each test then uses the Sidak-corrected level
``1 - (1 - significance) ** (1 / test_count)`` so the whole family keeps a false
alarm rate of ``significance``. Fix the seeds to make the results repeatable.

Worked example
--------------
Test a Lambertian BSDF at three incident angles, then check a smooth dielectric,
whose lobes are all delta, by the frequency of its reflect/refract choice:

>>> import numpy as np
>>> import bsdflab
>>> from bsdflab.testing import (albedo_sampled, albedo_uniform, bsdf_chi2,
...                              discrete_choice_chi2, spherical_directions)
>>> bsdf = bsdflab.Diffuse(0.8)
>>> angles = np.radians([0.0, 45.0, 87.0])
>>> for theta in angles:
...     wi = spherical_directions(theta, 0.0)
...     test = bsdf_chi2(bsdf, wi, sample_count=200_000, test_count=len(angles), seed=1)
...     assert test.run(), test.message        # message explains a failure
...     png = test.plot(f"/tmp/chi2_{np.degrees(theta):.0f}.png")   # optional picture
>>> wi = spherical_directions(np.radians(30.0), 0.0)
>>> a, b = albedo_uniform(bsdf, wi, n=200_000), albedo_sampled(bsdf, wi, n=200_000)
>>> bool(np.all(np.abs(a.mean - b.mean) < 4 * np.hypot(a.stderr, b.stderr)))
True
>>> glass = bsdflab.Dielectric(1.5, 1.0)
>>> R = bsdflab.optics.fresnel_reflectance(1.0, 1.0, 1.5).unpolarised   # normal incidence
>>> lobes = glass.sample(np.tile([0.0, 0.0, 1.0], (100_000, 1)), seed=2).lobe
>>> discrete_choice_chi2(lobes, {bsdflab.Lobe.DELTA_REFLECTION: R,
...                              bsdflab.Lobe.DELTA_TRANSMISSION: 1 - R}).passed
True

To test a sampler that is not a bsdflab BSDF, give ``ChiSquareTest`` two functions:
``sample_fn(n, seed) -> (n, 3)`` directions (rows of NaN or zeros for failed
samples) and ``pdf_fn(wo) -> (n,)`` densities; see its docstring.
"""
from bsdflab.testing.chi2 import ChiSquareTest, bsdf_chi2
from bsdflab.testing.consistency import ConsistencyReport, eval_pdf_consistency, reciprocity_error
from bsdflab.testing.directions import random_unit_vectors, spherical_directions
from bsdflab.testing.discrete import DiscreteChoiceResult, discrete_choice_chi2
from bsdflab.testing.furnace import AlbedoEstimate, albedo_sampled, albedo_uniform
from bsdflab.testing.image_compare import ImageTestResult, image_z_test, relative_mse  # noqa: F401  (image-level renderer checks)
from bsdflab.testing.stats import (
           PearsonResult,
           PooledCells,
           pearson_chi2,
           pool_low_expected,
           sidak_significance,
           sidak_z_limit,
)

__all__ = ["AlbedoEstimate", "ChiSquareTest", "ConsistencyReport", "DiscreteChoiceResult",
           "PearsonResult", "PooledCells", "albedo_sampled", "albedo_uniform", "bsdf_chi2",
           "discrete_choice_chi2", "eval_pdf_consistency", "pearson_chi2", "pool_low_expected",
           "random_unit_vectors", "reciprocity_error", "sidak_significance", "sidak_z_limit",
           "spherical_directions"]
