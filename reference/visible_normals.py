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
rounding (except at exactly normal incidence, where each code picks its own frame).
"""
from __future__ import annotations

import numpy as np

from .mitsuba_env import is_vectorised, mitsuba


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


def bsdflab_uniforms(u2: np.ndarray) -> np.ndarray:
    """bsdflab's direction uniforms (N, 2) that select the visible normal Mitsuba's
    warp selects for u2 (N, 2)."""
    x, y = mitsuba_disk_points(u2).T
    turn = np.mod(np.arctan2(y, -x) / (2 * np.pi), 1.0)
    turn = np.where(turn < 1.0, turn, 0.0)  # mod can round up to 1: the same angle as 0
    return np.stack([np.minimum(x * x + y * y, 1.0), turn], axis=1)
