"""Mitsuba 3's and bsdflab's GGX visible-normal warps, and uniforms on which they agree.

Both sample visible normals by Heitz's projected-disk construction: stretch wi to the
alpha = 1 configuration, take a point (p1, p2) of the unit disk, squash p2 towards the
visible half, p2 <- (1 - s) sqrt(1 - p1^2) + s p2 with s = (1 + cos theta) / 2, lift the
point onto the hemisphere around the stretched wi, and unstretch. They differ in two
places (bsdflab: core/src/microfacet.cpp; Mitsuba 3: include/mitsuba/render/microfacet.h,
``sample_visible_11``):

  * the disk point: bsdflab uses polar coordinates, r = sqrt(u_x), phi = 2 pi u_y;
    Mitsuba the concentric (Shirley-Chiu) map of (u_x, u_y);
  * the disk's first axis: bsdflab's t1 = normalize(-v_y, v_x, 0) (v the stretched wi)
    is the opposite of the axis Mitsuba's slope formula gives the disk's x.

So identical uniforms give different directions. With Mitsuba's disk point (x, y) for
(u_x, u_y), bsdflab's uniforms (x^2 + y^2, atan2(y, -x) / (2 pi) mod 1) give the same
disk point in bsdflab's frame, hence the same microfacet normal and sample, up to
rounding. One exception: where the stretched wi is within float32 reach of the normal
(sin^2 theta <= 4 epsilon, i.e. alpha tan theta_i <~ 5e-4), Mitsuba's frame takes
azimuth 0 instead of wi's; the mapping then rotates the disk point by wi's azimuth.

``warp_frame_shift`` bounds how far Mitsuba's own float32 rounding inside its warp (sin
theta of the stretched wi taken from its cosine) moves a sample; input perturbations of
bsdflab, which has no such step, cannot show it.
"""
from __future__ import annotations

import numpy as np

from bsdflab.lobes import Lobe
from bsdflab.reference.mitsuba_env import is_vectorised, mitsuba


def mitsuba_disk_points(u2: np.ndarray) -> np.ndarray:
    """(N, 2) points of Mitsuba's concentric square-to-disk map of u2 (N, 2), computed
    by Mitsuba in float32."""
    mi = mitsuba()
    u = np.ascontiguousarray(u2, dtype=np.float32)
    warp = mi.warp.square_to_uniform_disk_concentric
    if is_vectorised():
        p = warp(mi.Point2f(u[:, 0], u[:, 1]))
        return np.stack([np.array(p.x, dtype=np.float64), np.array(p.y, dtype=np.float64)], axis=1)
    return np.array([list(warp(mi.Point2f(*row.tolist()))) for row in u], dtype=np.float64)


def _flip(d: dict, wi: np.ndarray) -> np.ndarray:
    """Per row, the factors that turn wi into the upper-hemisphere direction the warp is
    given: a dielectric negates wi from below, a two-sided conductor mirrors its z."""
    below = (wi[:, 2] < 0)[:, None]
    return np.where(below, [-1.0, -1.0, -1.0] if d["type"] == "roughdielectric"
                    else [1.0, 1.0, -1.0], 1.0)


def bsdflab_uniforms(d: dict, u2: np.ndarray, wi: np.ndarray) -> np.ndarray:
    """bsdflab's direction uniforms (N, 2) that select the visible normal Mitsuba's warp
    selects for u2 (N, 2) and incident directions wi (N, 3), for the rough BSDF dict d.

    Beckmann: both codes invert the same slope CDFs (u_x along the incident azimuth, u_y
    across it; Heitz & d'Eon 2014), so the uniforms are Mitsuba's own, float32-rounded and
    clamped to its [1e-6, 1 - 1e-6]."""
    if d.get("distribution", "ggx") == "beckmann":
        u = np.asarray(u2, dtype=np.float32).astype(np.float64)
        return np.clip(u, np.float32(1e-6), np.float32(1 - 1e-6)).astype(np.float64)
    x, y = mitsuba_disk_points(u2).T
    # Mitsuba's frame azimuth is that of the stretched wi, except where its float32
    # sin^2 theta is at most 4 epsilon: there it takes azimuth 0 (Frame3f::sincos_phi).
    up = wi * _flip(d, wi)
    w32 = up.astype(np.float32)
    st = w32 * np.array([d["alpha"], d["alpha"], 1.0], dtype=np.float32)
    st = st / np.sqrt(np.sum(st * st, axis=1, dtype=np.float32))[:, None]
    fixed = st[:, 0] * st[:, 0] + st[:, 1] * st[:, 1] <= np.float32(4 * 2.0**-24)
    phi = np.where(fixed, np.arctan2(up[:, 1], up[:, 0]), 0.0)  # bsdflab's azimuth there
    c, s = np.cos(phi), np.sin(phi)
    p1, p2 = -x * c + y * s, x * s + y * c   # (-x, y) where the frames agree
    turn = np.mod(np.arctan2(p2, p1) / (2 * np.pi), 1.0)
    turn = np.where(turn < 1.0, turn, 0.0)  # mod can round up to 1: the same angle as 0
    return np.stack([np.minimum(p1 * p1 + p2 * p2, 1.0), turn], axis=1)


# -- Mitsuba's rounding inside its warp -----------------------------------------------------
def _unit(v: np.ndarray) -> np.ndarray:
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.nan_to_num(v / np.linalg.norm(v, axis=1, keepdims=True))


def _scatter(d: dict, wi: np.ndarray, m: np.ndarray, transmitted: np.ndarray) -> np.ndarray:
    """wi reflected about m, or refracted through it (zero past total internal reflection)."""
    c = np.einsum("ij,ij->i", wi, m)
    reflected = 2 * c[:, None] * m - wi
    if d["type"] != "roughdielectric":
        return reflected
    eta = d["int_ior"] / d["ext_ior"]
    eta_ti = np.where(c > 0, 1 / eta, eta)
    cos2_t = 1 - eta_ti**2 * (1 - c**2)
    cos_t = -np.sign(c) * np.sqrt(np.maximum(cos2_t, 0.0))
    refracted = np.where((cos2_t > 0)[:, None],
                         m * (c * eta_ti + cos_t)[:, None] - wi * eta_ti[:, None], 0.0)
    return np.where(transmitted[:, None], refracted, reflected)


def warp_frame_shift(d: dict, wi: np.ndarray, u1: np.ndarray, u2: np.ndarray, wo: np.ndarray,
                     lobe: np.ndarray, perturbation: float, channels) -> np.ndarray:
    """How far Mitsuba's float32 rounding inside its warp can move a sampled direction:
    bsdflab's sample (wo, lobe) for wi and bsdflab's uniforms (u1, u2).

    Mitsuba forms sin theta of the stretched wi as sqrt(1 - cos^2 theta), whose absolute
    rounding ``perturbation`` is amplified near the normal (where stretched wi lie when
    alpha is small): the warp's frame tilts as if wi were tilted in stretched space, while
    the reflection or refraction uses the true wi. Emulated here in float64 with bsdflab:
    sample for that tilted wi, take the microfacet normal it used, scatter the true wi.
    """
    from bsdflab.bsdfs import from_dict

    alpha, bsdf, flip = d["alpha"], from_dict(d), _flip(d, wi)
    stretched = _unit(wi * flip * np.array([alpha, alpha, 1.0]))
    sin2 = stretched[:, 0] ** 2 + stretched[:, 1] ** 2
    azimuth = _unit(np.where(sin2[:, None] > 0, stretched * [1.0, 1.0, 0.0], [1.0, 0.0, 0.0]))
    transmitted = lobe == int(Lobe.GLOSSY_TRANSMISSION)
    shift = np.zeros(len(wi))
    for sign in (-1.0, 1.0):
        sin2_p = np.clip(sin2 + sign * perturbation, 0.0, 1.0)
        tilted = azimuth * np.sqrt(sin2_p)[:, None] + [0.0, 0.0, 1.0] * np.sqrt(1 - sin2_p)[:, None]
        wi_p = _unit(tilted * [1 / alpha, 1 / alpha, 1.0]) * flip
        s = bsdf.sample(wi_p, u1, u2, wavelengths=channels)
        m = _unit(wi_p + s.wo * np.where(transmitted, s.eta, 1.0)[:, None])  # the half vector
        moved = _scatter(d, wi, m * np.where(m[:, 2] < 0, -1.0, 1.0)[:, None], transmitted)
        ok = (s.lobe == lobe) & (lobe != 0) & np.any(moved != 0, axis=1)
        shift = np.maximum(shift, np.where(ok, np.linalg.norm(moved - wo, axis=1), 0.0))
    return shift
