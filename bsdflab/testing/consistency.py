"""Deterministic consistency checks of a BSDF: reciprocity, and agreement of ``sample``
with ``eval`` and ``pdf``.

Errors are relative and symmetric, ``|a - b| / max(|a|, |b|)``: 0 when equal (or both
zero), 1 when one of them is zero and the other is not.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bsdflab.lobes import Lobe
from bsdflab.testing.directions import positive_int, random_unit_vectors, single_direction, spherical_directions
from bsdflab.util import args as check

__all__ = ["ConsistencyReport", "eval_pdf_consistency", "random_unit_vectors",
           "reciprocity_error", "spherical_directions"]


@dataclass(frozen=True)
class ConsistencyReport:
    """Largest disagreements found by ``eval_pdf_consistency``."""

    max_weight_error: float  # weight vs eval / pdf, over samples and channels
    max_pdf_error: float     # the sample's pdf vs pdf(wi, wo)
    checked: int             # samples compared (non-delta, not failed)
    skipped: int             # failed or delta-lobe samples, which have no density


def reciprocity_error(bsdf, wi, wo, wavelengths=None, lobes: Lobe | int = Lobe.ALL) -> np.ndarray:
    """Relative asymmetry ``|f(wi, wo) - f(wo, wi)| / max(|f(wi, wo)|, |f(wo, wi)|)``.

    f = eval / |cos theta_o| is the BSDF itself. To avoid dividing by a cosine near 0,
    both sides are multiplied by |cos theta_i| |cos theta_o|: the code compares
    ``eval(wi, wo) |cos theta_i|`` with ``eval(wo, wi) |cos theta_o|``. Pairs where
    either direction is exactly on the horizon then give 0 (nothing to compare).

    Refraction is not reciprocal in this plain sense (f_t / n^2 is), so expect
    non-zero values for glossy or diffuse transmission between different media.

    Parameters
    ----------
    bsdf : bsdflab.BSDF or any object with a compatible ``eval``
    wi, wo : array_like, shape (N, 3) or (3,)
        Direction pairs (unit, local frame); a single direction broadcasts.
    wavelengths : array_like or None
        As for ``eval``.
    lobes : Lobe
        Lobes to evaluate.

    Returns
    -------
    numpy.ndarray
        Shape (N, C): 0 for a reciprocal pair, up to 1.
    """
    a, b = check.direction_pair(wi, wo)
    forward = np.asarray(bsdf.eval(a, b, wavelengths=wavelengths, lobes=lobes)) * np.abs(a[:, 2:3])
    backward = np.asarray(bsdf.eval(b, a, wavelengths=wavelengths, lobes=lobes)) * np.abs(b[:, 2:3])
    return _relative_difference(forward, backward)


def eval_pdf_consistency(bsdf, wi, n: int = 100_000, seed: int = 0, wavelengths=None,
                         lobes: Lobe | int = Lobe.ALL) -> ConsistencyReport:
    """Check that ``sample`` agrees with ``eval`` and ``pdf`` for one incident direction.

    For every sampled wo from a non-delta lobe: the weight must equal
    ``eval(wi, wo) / pdf(wi, wo)`` (compared as ``weight * pdf`` vs ``eval``, so a zero
    pdf counts as a full error instead of dividing by zero) and the returned pdf must
    equal ``pdf(wi, wo)``.

    Parameters
    ----------
    bsdf : bsdflab.BSDF or any object with compatible ``sample``, ``eval``, ``pdf``
    wi : array_like, shape (3,)
        Incident direction (unit, local frame).
    n : int
        Number of samples. Default 100,000.
    seed : int
        Seed passed to ``sample``.
    wavelengths : array_like or None
        As for ``sample`` and ``eval``.
    lobes : Lobe
        Lobes to use.

    Returns
    -------
    ConsistencyReport

    Raises
    ------
    ValueError
        If no sample came from a non-delta lobe (e.g. a purely specular BSDF).
    """
    w = single_direction("wi", wi)
    n = positive_int("n", n)
    s = bsdf.sample(np.tile(w, (n, 1)), seed=check.seed(seed), wavelengths=wavelengths,
                    lobes=lobes)
    lobe = np.asarray(s.lobe).astype(np.int64)
    smooth = (lobe != 0) & ((lobe & int(Lobe.DELTA)) == 0)
    if not np.any(smooth):
        raise ValueError("no sample came from a non-delta lobe, so eval and pdf have nothing "
                         "to agree with; check delta lobes with discrete_choice_chi2 and "
                         "albedo_sampled")
    wo = np.asarray(s.wo)[smooth]
    value = np.asarray(bsdf.eval(w, wo, wavelengths=wavelengths, lobes=lobes))
    density = np.asarray(bsdf.pdf(w, wo, lobes=lobes))
    weight = np.asarray(s.weight)[smooth]
    weight_error = _relative_difference(weight * density[:, None], value)
    pdf_error = _relative_difference(np.asarray(s.pdf)[smooth], density)
    return ConsistencyReport(max_weight_error=float(weight_error.max()),
                             max_pdf_error=float(pdf_error.max()),
                             checked=int(smooth.sum()), skipped=int(n - smooth.sum()))


def _relative_difference(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    scale = np.maximum(np.abs(x), np.abs(y))
    with np.errstate(invalid="ignore", divide="ignore"):
        error = np.abs(x - y) / scale
    return np.where(scale > 0, error, 0.0)
