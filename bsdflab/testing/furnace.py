"""White-furnace integrals: the directional albedo of a BSDF by two independent estimators.

The albedo for incident direction wi is the integral over all outgoing directions of
f(wi, wo) |cos theta_o|, i.e. the fraction of energy scattered (reflected plus
transmitted). ``albedo_uniform`` integrates ``eval`` with uniform sphere sampling;
``albedo_sampled`` averages the ``sample`` weights. They must agree for a correct BSDF,
and equal 1 for an energy-conserving, non-absorbing one. Because ``eval`` is zero on
delta lobes, only ``albedo_sampled`` sees them.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bsdflab.lobes import Lobe
from bsdflab.testing.directions import positive_int, random_unit_vectors, single_direction
from bsdflab.util import args as check

__all__ = ["AlbedoEstimate", "albedo_sampled", "albedo_uniform"]


@dataclass(frozen=True)
class AlbedoEstimate:
    """A Monte Carlo albedo estimate per channel."""

    mean: np.ndarray    # (C,) estimated albedo
    stderr: np.ndarray  # (C,) standard error of the mean
    n: int              # number of samples

    def __str__(self) -> str:
        pairs = ", ".join(f"{m:.5f} +- {s:.5f}" for m, s in zip(self.mean, self.stderr))
        return f"albedo [{pairs}] (n = {self.n})"


def albedo_uniform(bsdf, wi, n: int = 1_000_000, seed: int = 0, wavelengths=None,
                   lobes: Lobe | int = Lobe.ALL) -> AlbedoEstimate:
    """Albedo from ``eval`` with uniformly distributed outgoing directions.

    Estimator: mean of ``eval(wi, wo) * 4 pi`` for wo uniform on the sphere (density
    1 / (4 pi)), so reflection and transmission are both covered. Independent of the
    BSDF's own sampling, so it also checks ``sample``. Blind to delta lobes.

    Parameters
    ----------
    bsdf : bsdflab.BSDF or any object with a compatible ``eval``
    wi : array_like, shape (3,)
        Incident direction (unit, local frame).
    n : int
        Number of samples. Default 1,000,000; the error shrinks as 1 / sqrt(n), and is
        large for peaked (glossy) lobes, which uniform sampling rarely hits.
    seed : int
        Seed of the outgoing directions.
    wavelengths : array_like or None
        As for ``eval``: None gives linear sRGB (3 channels).
    lobes : Lobe
        Lobes to evaluate.

    Returns
    -------
    AlbedoEstimate
    """
    w = single_direction("wi", wi)
    n = positive_int("n", n)
    wo = random_unit_vectors(n, seed)
    values = 4.0 * np.pi * np.asarray(bsdf.eval(w, wo, wavelengths=wavelengths, lobes=lobes))
    return _estimate(values)


def albedo_sampled(bsdf, wi, n: int = 1_000_000, seed: int = 0, wavelengths=None,
                   lobes: Lobe | int = Lobe.ALL) -> AlbedoEstimate:
    """Albedo as the mean ``sample`` weight (f |cos theta_o| / pdf); failed samples
    count as 0. Includes delta lobes.

    Parameters
    ----------
    bsdf : bsdflab.BSDF or any object with a compatible ``sample``
    wi : array_like, shape (3,)
        Incident direction (unit, local frame).
    n : int
        Number of samples. Default 1,000,000.
    seed : int
        Seed passed to ``sample``.
    wavelengths : array_like or None
        As for ``sample``: None gives linear sRGB (3 channels).
    lobes : Lobe
        Lobes to sample.

    Returns
    -------
    AlbedoEstimate
    """
    w = single_direction("wi", wi)
    n = positive_int("n", n)
    s = bsdf.sample(np.tile(w, (n, 1)), seed=check.seed(seed), wavelengths=wavelengths,
                    lobes=lobes)
    weight = np.asarray(s.weight, dtype=np.float64)
    # A failed sample carries no energy, whatever the weight array holds there.
    weight = np.where((np.asarray(s.lobe) == 0)[:, None], 0.0, weight)
    return _estimate(weight)


def _estimate(values: np.ndarray) -> AlbedoEstimate:
    """Mean and standard error per column of an (n, C) array of estimator values."""
    n = len(values)
    mean = values.mean(axis=0)
    stderr = values.std(axis=0, ddof=1) / np.sqrt(n) if n > 1 else np.full_like(mean, np.inf)
    return AlbedoEstimate(mean=mean, stderr=stderr, n=n)
