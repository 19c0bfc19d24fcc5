r"""Boundaries of the adding-doubling oracle: exact Fresnel powers of smooth interfaces,
the quadrature nodes in the slab medium, and the boundary layers.

Nodes. Light enters and leaves the slab medium (index n_s) only through smooth
interfaces, whose interior reflectance jumps to 1 at the critical cosine c and whose
transmittance goes like sqrt(mu - c) above it. Gauss-Legendre converges geometrically
only for analytic integrands, so the interval (0, 1] of slab cosines is cut at every
critical cosine into panels; a panel [c, b] that starts at a critical cosine is
parametrised by u in [0, 1] with mu = sqrt(c^2 + (b^2 - c^2) u^2), which makes
sqrt(mu^2 - c^2) = u sqrt(b^2 - c^2) analytic (the Fresnel terms and the refracted
exterior cosine are analytic in it).

Outer factors. A smooth interface maps a direction outside (cosine c_e, index n_e) to one
inside (c_s) by Snell's law. A beam of irradiance E outside becomes a beam of irradiance
T E inside (power is conserved, n^2-compression of radiance and of solid angle cancel);
radiance L_s inside leaving through it becomes T L_s (n_e / n_s)^2 outside (radiance / n^2
is conserved). These factors are applied once, outside the operator algebra, so a
boundary layer's transmission operators are the identity in slab coordinates.
"""
from __future__ import annotations

import numpy as np

from bsdflab.oracles import _ad_operators as op


def fresnel_reflectance(n1: float, n2: float, cos1) -> np.ndarray:
    """Unpolarised reflectance (|r_s|^2 + |r_p|^2) / 2 for light in medium n1 arriving
    at cosine cos1 in (0, 1] on medium n2; 1 beyond the critical angle."""
    c1 = np.clip(np.asarray(cos1, dtype=np.float64), 0.0, 1.0)
    sin2_t = (n1 / n2) ** 2 * (1.0 - c1 * c1)
    tir = sin2_t >= 1.0
    c2 = np.sqrt(np.where(tir, 0.0, 1.0 - sin2_t))
    with np.errstate(invalid="ignore", divide="ignore"):
        rs = (n1 * c1 - n2 * c2) / (n1 * c1 + n2 * c2)
        rp = (n2 * c1 - n1 * c2) / (n2 * c1 + n1 * c2)
        r = 0.5 * (rs * rs + rp * rp)
    return np.where(tir | ~np.isfinite(r), 1.0, r)


def refracted_cosine(n_from: float, n_to: float, cos_from) -> np.ndarray:
    """Cosine after refraction from n_from into n_to; 0 where totally reflected."""
    c = np.asarray(cos_from, dtype=np.float64)
    s2 = 1.0 - (n_from / n_to) ** 2 * (1.0 - c * c)
    return np.sqrt(np.maximum(s2, 0.0))


def critical_cosine(n_slab: float, n_outside: float) -> float | None:
    """Slab cosine of the critical angle toward a rarer outside medium (None if none)."""
    if n_outside >= n_slab:
        return None
    r = n_outside / n_slab
    return float(np.sqrt((1.0 - r) * (1.0 + r)))


def nodes(per_panel: int, breaks) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre nodes and weights on (0, 1] cut at the critical cosines `breaks`
    (module docstring), per_panel nodes in each panel."""
    cuts = sorted({0.0, 1.0, *(float(b) for b in breaks if 0.0 < b < 1.0)})
    x, w = np.polynomial.legendre.leggauss(per_panel)
    u, wu = 0.5 * (x + 1.0), 0.5 * w
    mus, weights = [], []
    for a, b in zip(cuts[:-1], cuts[1:]):
        if a == 0.0:
            mus.append(b * u)
            weights.append(b * wu)
        else:  # mu = sqrt(a^2 + (b^2 - a^2) u^2)
            span = (b - a) * (b + a)
            mu = np.sqrt(a * a + span * u * u)
            mus.append(mu)
            weights.append(wu * span * u / mu)
    return np.concatenate(mus), np.concatenate(weights)


def flux_weights(mu: np.ndarray, weights: np.ndarray, orders: int) -> np.ndarray:
    """W (M, N) = pi (1 + [m = 0]) mu w of the operator algebra."""
    scale = np.full(orders, np.pi)
    scale[0] = 2.0 * np.pi
    return scale[:, None] * (mu * weights)[None, :]


def _diagonal(values) -> op.Operator:
    """A delta-only operator from its values at (nodes, outputs, inputs)."""
    return op.Operator(*values)


def top_layer(cos, n_slab: float, n_ext: float, g: op.Grid) -> op.LayerOperators:
    """The smooth top seen from the slab: its interior reflectance as the bottom-side
    reflection; transmissions the identity (outer factors applied by the caller)."""
    one = op.identity(g)
    inside = _diagonal(fresnel_reflectance(n_slab, n_ext, c) for c in cos)
    return op.LayerOperators(op.Operator(), one, inside, one)


def smooth_base_layer(cos, n_slab: float, n_below: float, g: op.Grid) -> op.LayerOperators:
    """A smooth interface to a medium of index n_below under the last slab."""
    one = op.identity(g)
    inside = _diagonal(fresnel_reflectance(n_slab, n_below, c) for c in cos)
    return op.LayerOperators(inside, one, op.Operator(), one)


def lambertian_base_layer(albedo, g: op.Grid) -> op.LayerOperators:
    """An opaque Lambertian base of albedo (L,): kernel albedo / pi in order 0 only."""
    L, M = g.batch
    k = np.zeros((L, M, 1, 1))
    k[:, 0] = np.asarray(albedo, dtype=np.float64)[:, None, None] / np.pi
    shapes = ((g.n, g.n), (g.n_out, g.n), (g.n, g.n_in))
    K, Kr, Kc = (np.broadcast_to(k, (L, M) + s) for s in shapes)
    R = op.Operator(K=K, Kr=Kr, Kc=Kc, Kp=np.broadcast_to(k[..., 0], (L, M, len(g.pr))))
    return op.LayerOperators(R, op.Operator(), op.Operator(), op.Operator())
