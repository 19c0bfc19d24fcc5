"""Random BSDF queries for cross-checks (direction pairs and sampling uniforms), and
bsdflab's answers to them.

Every value is rounded to float32 (and handed back as float64), so a float32 renderer
and bsdflab see bit-identical inputs and any difference comes from their arithmetic.

wi covers both hemispheres in equal shares; a fraction of wi and wo is grazing
(|cos theta| log-uniform in [1e-6, 1e-2]); for a refracting interface a further fraction
of wi lies near the critical angle on the dense side, where float32 Snell's law is
ill-conditioned (see ``near_critical_cos``). Draws closer to the critical angle than
float32 can resolve (its spacing of cos theta is ~6e-8) land on the nearest float32
directions on either side: as close as a float32 renderer can get.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

GRAZING_FRACTION = 0.1
GRAZING_COS_RANGE = (1e-6, 1e-2)
NEAR_CRITICAL_FRACTION = 0.02
# cos^2(theta_t) = 1 - eta_ti^2 sin^2(theta_i) is drawn log-uniform in magnitude over this
# range, with either sign (just before and just past total internal reflection).
NEAR_CRITICAL_COS2_RANGE = (1e-9, 3e-2)


@dataclass(frozen=True)
class Queries:
    wi: np.ndarray  # (N, 3) incident directions
    wo: np.ndarray  # (N, 3) outgoing directions for eval / pdf
    u1: np.ndarray  # (N,) lobe-selection uniform for sample
    u2: np.ndarray  # (N, 2) direction uniforms for sample


def _round32(a) -> np.ndarray:
    return np.asarray(a, dtype=np.float32).astype(np.float64)


def _sphere(rng, n) -> np.ndarray:
    v = rng.normal(size=(n, 3))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def _with_cos(rng, cos_theta) -> np.ndarray:
    """Directions with the given signed cos(theta) and random azimuth."""
    phi = rng.uniform(0, 2 * np.pi, len(cos_theta))
    sin_theta = np.sqrt(np.maximum(0.0, 1 - cos_theta**2))
    return np.stack([sin_theta * np.cos(phi), sin_theta * np.sin(phi), cos_theta], axis=1)


def _log_uniform(rng, lo, hi, n) -> np.ndarray:
    return np.exp(rng.uniform(np.log(lo), np.log(hi), n))


def near_critical_cos(cos2_t, eta_ti) -> np.ndarray:
    """|cos theta_i| at which light going from the dense side (eta_ti = n_i / n_t > 1)
    refracts with cos^2(theta_t) = cos2_t (negative: past total internal reflection)."""
    return np.sqrt(1 - (1 - np.asarray(cos2_t)) / eta_ti**2)


def draw_queries(n: int, seed: int = 0, critical: tuple[float, int] | None = None) -> Queries:
    """n random queries from numpy's PCG64 stream ``seed``.

    critical: (eta_ti, side) for an interface whose critical angle exists for light
    arriving from ``side`` (+1 above, -1 below) with relative index eta_ti > 1.
    """
    if int(n) != n or n < 1:
        raise ValueError(f"n must be a positive integer, got {n!r}")
    n = int(n)
    rng = np.random.default_rng(seed)
    wi, wo = _sphere(rng, n), _sphere(rng, n)

    n_graze = int(round(GRAZING_FRACTION * n))
    for w in (wi, wo):
        idx = rng.choice(n, n_graze, replace=False)
        sign = rng.choice([-1.0, 1.0], n_graze)
        w[idx] = _with_cos(rng, sign * _log_uniform(rng, *GRAZING_COS_RANGE, n_graze))

    # wi: both hemispheres in equal shares (grazing ones included).
    half = rng.permutation(n)[: n // 2]
    wi[:, 2] = np.abs(wi[:, 2])
    wi[half, 2] *= -1

    if critical is not None:
        eta_ti, side = critical
        if not eta_ti > 1 or side not in (-1, 1):
            raise ValueError("critical must be (eta_ti > 1, side +1 or -1)")
        n_crit = max(1, int(round(NEAR_CRITICAL_FRACTION * n)))
        idx = rng.choice(n, n_crit, replace=False)
        sign = rng.choice([-1.0, 1.0], n_crit)
        cos2_t = sign * _log_uniform(rng, *NEAR_CRITICAL_COS2_RANGE, n_crit)
        wi[idx] = _with_cos(rng, side * near_critical_cos(cos2_t, eta_ti))

    return Queries(wi=_round32(wi), wo=_round32(wo), u1=_round32(rng.random(n)),
                   u2=_round32(rng.random((n, 2))))


def bsdflab_answers(bsdf, q: Queries, channels) -> dict[str, np.ndarray]:
    """bsdflab's eval and pdf of (wi, wo) and its sample for (wi, u1, u2), as a dict with
    keys eval, pdf, wo, weight, sample_pdf, lobe, eta. channels: wavelengths (nm) or None
    for sRGB."""
    s = bsdf.sample(q.wi, q.u1, q.u2, wavelengths=channels)
    return {"eval": bsdf.eval(q.wi, q.wo, wavelengths=channels), "pdf": bsdf.pdf(q.wi, q.wo),
            "wo": s.wo, "weight": s.weight, "sample_pdf": s.pdf,
            "lobe": s.lobe.astype(np.int64), "eta": s.eta}
