"""Heitz et al. 2016's stochastic random walk on a Smith microsurface: the exact
multiple-scattering reference for rough conductors and dielectrics.

E. Heitz, J. Hanika, E. d'Eon, C. Dachsbacher, "Multiple-scattering microfacet BSDFs with
the Smith model", ACM TOG 35(4), 2016. Written here from the paper with numpy alone -- it
shares no code with bsdflab's C++ core, which it checks.

The microsurface is a random height field whose normals follow D (GGX or Beckmann) with
Smith's uncorrelated heights (uniform on [-1, 1]; the results do not depend on the height
distribution). A walk starts above the surface travelling along -wi, and repeatedly

  1. draws the height of its next intersection from the Smith masking statistics of its
     direction (escaping with probability G1(w, h) = C1(h)^Lambda(w) when it travels away),
  2. draws the microfacet it hits from the distribution of normals visible from where it
     came, and
  3. reflects (conductor: weight times F(w.m) per channel) or, for a dielectric, reflects
     with probability F and refracts otherwise (Fresnel of the facet, either side).

A walk below a dielectric's microsurface sees the mirrored problem (heights and directions
negated, relative index inverted), as in the paper. Walks are vectorised: the Python loop
runs over scattering orders, never over walks.

Energies are flux fractions (a transmitted walk carries its energy without the radiance
scaling (n_i / n_t)^2). Scattering order 1 alone is the *height-correlated* single-
scattering BSDF (G2 = 1 / (1 + Lambda_i + Lambda_o) in reflection, the Beta function
B(1 + Lambda_i, 1 + Lambda_o) in transmission: ``single_scattering``), not the separable
G1 G1 of bsdflab's (and Mitsuba's) microfacet lobes.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import special

DISTRIBUTIONS = ("ggx", "beckmann")


# -- the microsurface statistics ------------------------------------------------------------
def _check(distribution: str, alpha: float) -> None:
    if distribution not in DISTRIBUTIONS:
        raise ValueError(f"distribution must be one of {DISTRIBUTIONS}, got {distribution!r}")
    if not (np.isfinite(alpha) and 1e-4 <= alpha <= 4):
        raise ValueError(f"alpha must be in [1e-4, 4], got {alpha!r}")


def ndf(distribution: str, alpha: float, m: np.ndarray) -> np.ndarray:
    """D(m) for unit normals m (N, 3); zero below the horizon."""
    z = m[..., 2]
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        z2 = z * z
        tan2 = np.maximum(0.0, 1.0 - z2) / z2
        a2 = alpha * alpha
        if distribution == "ggx":
            d = 1.0 / (np.pi * a2 * z2 * z2 * (1.0 + tan2 / a2) ** 2)
        else:
            d = np.exp(-tan2 / a2) / (np.pi * a2 * z2 * z2)
    return np.where((z > 0) & np.isfinite(d), d, 0.0)


def smith_lambda(distribution: str, alpha: float, w: np.ndarray) -> np.ndarray:
    """Smith's Lambda of directions w (N, 3), signed as in Heitz et al.: for w.z < 0,
    Lambda(w) = -1 - Lambda(-w)."""
    z = w[..., 2]
    sin = np.sqrt(np.maximum(0.0, w[..., 0] ** 2 + w[..., 1] ** 2))
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        if distribution == "ggx":
            up = 0.5 * (np.sqrt(1.0 + (alpha * sin / np.abs(z)) ** 2) - 1.0)
        else:
            a = np.abs(z) / (alpha * sin)  # 1 / (alpha tan theta)
            up = np.where(a > 26.0, 0.0,
                          0.5 * (np.exp(-a * a) / (a * np.sqrt(np.pi)) - special.erfc(a)))
    up = np.where(sin == 0, 0.0, np.where(z == 0, np.inf, up))
    return np.where(z >= 0, up, -1.0 - up)


def _newton_increasing(f, lo: np.ndarray, hi: np.ndarray, iterations: int = 60) -> np.ndarray:
    """Roots of increasing functions f(x) -> (value, slope) on [lo, hi], vectorised:
    Newton steps that fall back to bisection outside the bracket."""
    x = 0.5 * (lo + hi)
    for _ in range(iterations):
        value, slope = f(x)
        lo = np.where(value < 0, x, lo)
        hi = np.where(value < 0, hi, x)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            nxt = x - value / slope  # a zero slope (the tails) falls back to bisection
        nxt = np.where((nxt > lo) & (nxt < hi), nxt, 0.5 * (lo + hi))
        done = np.all(np.abs(nxt - x) <= 1e-13 * np.maximum(1.0, np.abs(x)))
        x = nxt
        if done:
            break
    return x


def _beckmann_slope(cot: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Visible slope along the azimuth for the alpha = 1 Beckmann surface seen from
    cot(theta) (any sign: directions below the horizon too): density (cot - s) e^{-s^2} on
    s < cot, CDF proportional to cot sqrt(pi) erfc(-s) + e^{-s^2}."""
    sp = np.sqrt(np.pi)
    cot = np.minimum(cot, 1e6)
    cdf = lambda s: cot * sp * special.erfc(-s) + np.exp(-s * s)
    target = u * cdf(cot)
    f = lambda s: (cdf(s) - target, 2.0 * np.exp(-s * s) * (cot - s))
    return _newton_increasing(f, np.minimum(cot, 0.0) - 9.0, cot)


def sample_visible_normals(distribution: str, alpha: float, wv: np.ndarray,
                           u: np.ndarray) -> np.ndarray:
    """Normals m (upper hemisphere) distributed as max(0, wv.m) D(m) for directions wv
    (N, 3) of either hemisphere (not straight down) and uniforms u (N, 2)."""
    st = wv * np.array([alpha, alpha, 1.0])
    st = st / np.linalg.norm(st, axis=1, keepdims=True)
    sin = np.hypot(st[:, 0], st[:, 1])
    safe = np.where(sin > 0, sin, 1.0)
    cos_phi, sin_phi = np.where(sin > 0, st[:, 0] / safe, 1.0), np.where(sin > 0, st[:, 1] / safe, 0.0)
    if distribution == "ggx":
        # Heitz 2018's projected hemisphere; valid for directions below the horizon too
        # (the squashed disk becomes the disk minus the ellipse of the cut).
        t1 = np.stack([-sin_phi, cos_phi, np.zeros_like(sin)], axis=1)
        t2 = np.cross(st, t1)
        r, phi = np.sqrt(u[:, 0]), 2 * np.pi * u[:, 1]
        p1, p2 = r * np.cos(phi), r * np.sin(phi)
        s = 0.5 * (1.0 + st[:, 2])
        p2 = (1.0 - s) * np.sqrt(np.maximum(0.0, 1.0 - p1 * p1)) + s * p2
        n = (t1 * p1[:, None] + t2 * p2[:, None]
             + st * np.sqrt(np.maximum(0.0, 1.0 - p1 * p1 - p2 * p2))[:, None])
        m = np.stack([alpha * n[:, 0], alpha * n[:, 1], np.maximum(n[:, 2], 0.0)], axis=1)
    else:
        with np.errstate(divide="ignore"):
            cot = np.where(sin > 0, st[:, 2] / safe, np.inf)
        sx = _beckmann_slope(cot, np.clip(u[:, 0], 1e-15, 1 - 1e-15))
        sy = special.ndtri(np.clip(u[:, 1], 1e-15, 1 - 1e-15)) / np.sqrt(2.0)
        x = alpha * (cos_phi * sx - sin_phi * sy)
        y = alpha * (sin_phi * sx + cos_phi * sy)
        m = np.stack([-x, -y, np.ones_like(x)], axis=1)
    return m / np.linalg.norm(m, axis=1, keepdims=True)


# -- Fresnel (independent of bsdflab.optics) ---------------------------------------------
def _fresnel_dielectric(cos_i: np.ndarray, eta: np.ndarray):
    """(R, cos_t) for |cos_i| on the incident side and eta = n_t / n_i; cos_t = 0 under TIR."""
    sin2_t = (1.0 - cos_i * cos_i) / (eta * eta)
    tir = sin2_t >= 1.0
    cos_t = np.sqrt(np.maximum(0.0, 1.0 - sin2_t))
    rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    return np.where(tir, 1.0, 0.5 * (rs * rs + rp * rp)), np.where(tir, 0.0, cos_t)


def _fresnel_conductor(cos_i: np.ndarray, n: np.ndarray) -> np.ndarray:
    """Unpolarised reflectance (N, C) of a complex relative index n (C,) at cos_i (N,)."""
    c = cos_i[:, None].astype(complex)
    s2 = 1.0 - c * c
    ct = np.sqrt(n[None, :] ** 2 - s2) / n[None, :]
    rs = (c - n * ct) / (c + n * ct)
    rp = (n * c - ct) / (n * c + ct)
    return 0.5 * (np.abs(rs) ** 2 + np.abs(rp) ** 2)


# -- the walk -----------------------------------------------------------------------------
def _c1(h):
    return np.clip(0.5 * (h + 1.0), 0.0, 1.0)


def _next_height(lam: np.ndarray, wz: np.ndarray, h: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Height of the next intersection for travel directions with Lambda lam and
    z-component wz from height h; +inf where the walk escapes upwards."""
    c = _c1(h)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        escape_up = (wz > 0) & (u > 1.0 - c ** lam)
        c_new = c / (1.0 - u) ** (1.0 / lam)
    h_new = 2.0 * np.clip(c_new, 0.0, 1.0) - 1.0
    h_new = np.where(wz == 0, h, h_new)
    return np.where(escape_up, np.inf, h_new)


@dataclass(frozen=True)
class Walks:
    """Outcomes of N walks: exit direction, side (+1 above, -1 below, 0 unfinished),
    energy per channel (N, C) and scattering order (bounces before leaving)."""

    wo: np.ndarray
    side: np.ndarray
    energy: np.ndarray
    order: np.ndarray

    def moments(self, mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Mean and standard error (C,) of the energy leaving through ``mask`` (N,)."""
        e = np.where(mask[:, None], self.energy, 0.0)
        n = len(e)
        return e.mean(axis=0), e.std(axis=0, ddof=1) / np.sqrt(n)


def random_walk(wi, n_walks: int, alpha: float, distribution: str = "ggx", *,
                eta: float | None = None, conductor_index=None, seed: int = 0,
                max_order: int = 10_000) -> Walks:
    """Walk ``n_walks`` rays arriving from direction wi (3,) or one per walk (n_walks, 3)
    (pointing away from the surface; wi.z < 0: from inside a dielectric).

    eta: n_int / n_ext of a dielectric microsurface; else a conductor with complex relative
    index ``conductor_index`` per channel (None: white facets, F = 1).
    """
    _check(distribution, alpha)
    N = int(n_walks)
    wi = np.asarray(wi, dtype=float)
    wi = np.broadcast_to(wi if wi.ndim == 2 else wi.reshape(1, 3), (N, 3))
    norm = np.linalg.norm(wi, axis=1, keepdims=True)
    if not np.all(np.isfinite(norm) & (norm > 0)) or np.any(wi[:, 2] == 0):
        raise ValueError("wi must be finite non-zero directions off the horizon")
    wi = wi / norm
    dielectric = eta is not None
    if dielectric and not (np.isfinite(eta) and eta > 0 and eta != 1):
        raise ValueError(f"eta must be finite, > 0 and != 1, got {eta!r}")
    if not dielectric and np.any(wi[:, 2] <= 0):
        raise ValueError("a conductor is lit from above (wi.z > 0)")
    n_ind = None if conductor_index is None else np.atleast_1d(np.asarray(conductor_index, complex))
    C = 1 if n_ind is None else len(n_ind)
    rng = np.random.default_rng(seed)
    w = -wi.copy()
    outside = wi[:, 2] > 0
    h = np.where(outside, 2.0, -2.0)  # start beyond the height range
    energy = np.ones((N, C))
    wo, side, order = np.zeros((N, 3)), np.zeros(N, dtype=int), np.zeros(N, dtype=int)
    live = np.arange(N)
    for k in range(max_order + 1):
        if live.size == 0:
            break
        wl, hl, out = w[live], h[live], outside[live]
        # Below the microsurface the walk sees it mirrored: negate heights and directions.
        sgn = np.where(out, 1.0, -1.0)
        wv = wl * sgn[:, None]
        lam = smith_lambda(distribution, alpha, wv)
        hn = _next_height(lam, wv[:, 2], hl * sgn, rng.random(live.size))
        left = ~np.isfinite(hn)
        done = live[left]
        wo[done], side[done], order[done] = wl[left], np.where(out[left], 1, -1), k
        keep = ~left
        live, wl, out, sgn, hn = live[keep], wl[keep], out[keep], sgn[keep], hn[keep]
        if k == max_order or live.size == 0:
            break
        h[live] = hn * sgn
        came = -wl                         # towards where the walk came from
        m = sample_visible_normals(distribution, alpha, came * sgn[:, None],
                                   rng.random((live.size, 2))) * sgn[:, None]
        cos = np.einsum("ij,ij->i", came, m)
        reflected = 2.0 * cos[:, None] * m - came
        if not dielectric:
            if n_ind is not None:
                energy[live] *= _fresnel_conductor(np.abs(cos), n_ind)
            w[live] = reflected
            continue
        eta_t = np.where(out, eta, 1.0 / eta)  # n_t / n_i at the facet
        F, cos_t = _fresnel_dielectric(np.abs(cos), eta_t)
        refract = rng.random(live.size) >= F
        refracted = -came / eta_t[:, None] + m * (cos / eta_t - np.sign(cos) * cos_t)[:, None]
        new = np.where(refract[:, None], refracted, reflected)
        w[live] = new / np.linalg.norm(new, axis=1, keepdims=True)
        outside[live] = np.where(refract, ~out, out)
    return Walks(wo=wo, side=side, energy=energy, order=order)


# -- the order-1 closed form ----------------------------------------------------------------
def single_scattering(wi: np.ndarray, wo: np.ndarray, alpha: float, distribution: str = "ggx",
                      *, eta: float | None = None) -> np.ndarray:
    """The height-correlated single-scattering BSDF times |cos theta_o| (flux units: no
    radiance scaling), (N,), for a dielectric (eta) or a white conductor (eta None):
    what the walks' scattering order 1 estimates."""
    wi, wo = np.atleast_2d(wi), np.atleast_2d(wo)
    reflect = wi[:, 2] * wo[:, 2] > 0
    lam_i = smith_lambda(distribution, alpha, wi * np.sign(wi[:, 2])[:, None])
    lam_o = smith_lambda(distribution, alpha, wo * np.sign(wo[:, 2])[:, None])
    e = np.ones(len(wi)) if eta is None else np.where(wi[:, 2] > 0, eta, 1.0 / eta)  # n_o / n_i
    m = np.where(reflect[:, None], wi + wo, wi + wo * e[:, None])
    m = m / np.linalg.norm(m, axis=1, keepdims=True)
    m = m * np.where(m[:, 2] < 0, -1.0, 1.0)[:, None]
    ci, co = np.einsum("ij,ij->i", wi, m), np.einsum("ij,ij->i", wo, m)
    ok = (ci * wi[:, 2] > 0) & (co * wo[:, 2] > 0)
    D = ndf(distribution, alpha, m)
    if eta is None:
        F = np.ones(len(wi))
    else:
        F, _ = _fresnel_dielectric(np.abs(ci), e)
    g_r = 1.0 / (1.0 + lam_i + lam_o)
    g_t = special.beta(1.0 + lam_i, 1.0 + lam_o)
    with np.errstate(divide="ignore", invalid="ignore"):
        fr = F * D * g_r / (4.0 * np.abs(wi[:, 2]))
        ft = (np.abs(ci * co) / np.abs(wi[:, 2]) * e * e * (1.0 - F) * D * g_t
              / (ci + e * co) ** 2)
    v = np.where(reflect, fr, ft if eta is not None else 0.0)
    return np.where(ok & np.isfinite(v), v, 0.0)
