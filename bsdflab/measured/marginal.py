"""A conditional 2D density on the unit square, bilinear between grid nodes, sampled by its
continuous marginal then conditional CDF (numpy; the C++ twin is core/src/measured_warp.cpp).

This is the warp the RGL format is defined by (Dupuy & Jakob 2018, section 5; Mitsuba 3's
``Marginal2D<Float, Dim, Continuous=true>`` in ``include/mitsuba/core/distr_2d.h``): the
data ``(*params, h, w)`` holds one ``h x w`` grid of node values per parameter node; nodes
sit at ``(i / (w - 1), j / (h - 1))``; a query between parameter nodes blends the
neighbouring slices linearly (clamped at the ends). With ``normalize`` every slice is
scaled to integrate to 1 over the square, so ``eval`` is a density. Point ``x`` runs
along the last axis (width), ``y`` along the one before. Tables are stored as float32,
as a float32 reader holds them, and CDFs are accumulated in float64 then rounded.
"""
from __future__ import annotations

import numpy as np


class Marginal2D:
    """Bilinear density on [0, 1]^2 conditioned on ``len(params)`` parameters.

    Parameters
    ----------
    data : array (*param_res, h, w)
        Node values (>= 0 for sampling); h, w >= 2.
    params : sequence of 1-D arrays
        The node positions of each parameter (increasing); one array per leading axis.
    normalize : bool
        Scale each slice to integrate to 1 (a density) -- or keep raw values (an interpolant).
    """

    def __init__(self, data, params=(), normalize: bool = True):
        data = np.asarray(data, dtype=np.float64)
        self.params = [np.asarray(p, dtype=np.float32).astype(np.float64) for p in params]
        if data.ndim != 2 + len(self.params):
            raise ValueError(f"data needs {2 + len(self.params)} dimensions, got {data.ndim}")
        *res, h, w = data.shape
        if h < 2 or w < 2:
            raise ValueError(f"the 2D grid must be at least 2 x 2, got {h} x {w}")
        if tuple(res) != tuple(len(p) for p in self.params):
            raise ValueError(f"data's parameter axes {tuple(res)} do not match the parameter "
                             f"node counts {tuple(len(p) for p in self.params)}")
        self.h, self.w, self.normalized = h, w, normalize
        # Slice strides (a single-node parameter has stride 0: never interpolated).
        self.strides, n = [0] * len(res), 1
        for i in range(len(res) - 1, -1, -1):
            self.strides[i] = n if res[i] > 1 else 0
            n *= res[i]
        slices = data.reshape(n, h, w)
        sx, sy = 0.5 / (w - 1), 0.5 / (h - 1)
        cond = np.cumsum(sx * (slices[:, :, :-1] + slices[:, :, 1:]), axis=2)    # (n, h, w-1)
        marg = np.cumsum(sy * (cond[:, :-1, -1] + cond[:, 1:, -1]), axis=1)      # (n, h-1)
        norm = 1.0 / marg[:, -1] if normalize else np.ones(n)
        with np.errstate(divide="ignore", invalid="ignore"):
            norm = np.where(np.isfinite(norm), norm, 0.0)
        f32 = lambda a: a.astype(np.float32).astype(np.float64)
        self.norm_f32 = f32(norm)
        self.data = f32(f32(slices) * self.norm_f32[:, None, None])
        self.cond = f32(f32(cond) * self.norm_f32[:, None, None])
        self.marg = f32(f32(marg) * self.norm_f32[:, None])

    # -- parameter interpolation --------------------------------------------------------
    def _corners(self, param):
        """[(slice index (N,), weight (N,)), ...] over the 2^D neighbouring slices."""
        n = len(param[0]) if param else 1
        corners = [(np.zeros(n, dtype=np.int64), np.ones(n))]
        for dim, values in enumerate(self.params):
            if len(values) == 1:
                continue
            p = np.asarray(param[dim], dtype=np.float64)
            idx = np.clip(np.searchsorted(values, p, side="left") - 1, 0, len(values) - 2)
            p0, p1 = values[idx], values[idx + 1]
            with np.errstate(invalid="ignore"):
                w1 = np.clip((p - p0) / (p1 - p0), 0.0, 1.0)
            w1 = np.where(np.isfinite(w1), w1, 0.0)
            step = self.strides[dim]
            corners = [(s + idx * step, wt * (1 - w1)) for s, wt in corners] + \
                      [(s + (idx + 1) * step, wt * w1) for s, wt in corners]
        return corners

    @staticmethod
    def _lookup(table, corners, *index):
        out = 0.0
        for s, wt in corners:
            v = table[(s, *index)]
            out = out + wt.reshape(wt.shape + (1,) * (v.ndim - wt.ndim)) * v
        return out

    # -- the three operations ----------------------------------------------------------
    def eval(self, pos, param=()):
        """Interpolated (density) value at points ``pos`` (N, 2)."""
        corners = self._corners(param)
        x, y, ix, iy = self._patch(pos)
        v = [self._lookup(self.data, corners, iy + dy, ix + dx) for dy in (0, 1) for dx in (0, 1)]
        return (1 - y) * ((1 - x) * v[0] + x * v[1]) + y * ((1 - x) * v[2] + x * v[3])

    def _patch(self, pos):
        pos = np.clip(np.asarray(pos, dtype=np.float64), 0.0, 1.0)
        px, py = pos[:, 0] * (self.w - 1), pos[:, 1] * (self.h - 1)
        ix = np.minimum(px.astype(np.int64), self.w - 2)
        iy = np.minimum(py.astype(np.int64), self.h - 2)
        return px - ix, py - iy, ix, iy

    def sample(self, u, param=()):
        """Warp uniforms ``u`` (N, 2) to points on the square; returns (points, density)."""
        corners = self._corners(param)
        eps = np.finfo(np.float32).eps
        u = np.clip(np.asarray(u, dtype=np.float64), eps, 1 - eps)
        ux, uy = u[:, 0].copy(), u[:, 1].copy()
        marg = self._lookup(self.marg, corners)                               # (N, h-1)
        if not self.normalized:
            uy *= marg[:, -1]
        row = np.minimum((marg < uy[:, None]).sum(axis=1), self.h - 2)
        k = np.arange(len(ux))
        uy -= np.where(row > 0, marg[k, np.maximum(row - 1, 0)], 0.0)
        r0 = self._lookup(self.cond, corners, row, self.w - 2)
        r1 = self._lookup(self.cond, corners, row + 1, self.w - 2)
        ty = _sample_segment(uy, self.h - 1, r0, r1)
        ux *= (1 - ty) * r0 + ty * r1
        c_lo = self._lookup(self.cond, corners, row)                            # (N, w-1)
        c_hi = self._lookup(self.cond, corners, row + 1)
        cdf = (1 - ty)[:, None] * c_lo + ty[:, None] * c_hi
        col = np.minimum((cdf[:, :-1] < ux[:, None]).sum(axis=1), self.w - 2)
        ux -= np.where(col > 0, cdf[k, np.maximum(col - 1, 0)], 0.0)
        v00 = self._lookup(self.data, corners, row, col)
        v10 = self._lookup(self.data, corners, row, col + 1)
        v01 = self._lookup(self.data, corners, row + 1, col)
        v11 = self._lookup(self.data, corners, row + 1, col + 1)
        c0, c1 = (1 - ty) * v00 + ty * v01, (1 - ty) * v10 + ty * v11
        tx = _sample_segment(ux, self.w - 1, c0, c1)
        points = np.stack([(col + tx) / (self.w - 1), (row + ty) / (self.h - 1)], axis=1)
        return points, (1 - tx) * c0 + tx * c1

    def invert(self, pos, param=()):
        """Inverse of ``sample``: points (N, 2) back to uniforms; returns (uniforms, density)."""
        corners = self._corners(param)
        fx, fy, ix, iy = self._patch(pos)
        v00 = self._lookup(self.data, corners, iy, ix)
        v10 = self._lookup(self.data, corners, iy, ix + 1)
        v01 = self._lookup(self.data, corners, iy + 1, ix)
        v11 = self._lookup(self.data, corners, iy + 1, ix + 1)
        c0, c1 = (1 - fy) * v00 + fy * v01, (1 - fy) * v10 + fy * v11
        pdf = (1 - fx) * c0 + fx * c1
        x = fx * (c0 + (c1 - c0) * 0.5 * fx) / (self.w - 1)
        prev = np.maximum(ix - 1, 0)
        lo = self._lookup(self.cond, corners, iy, prev)
        hi = self._lookup(self.cond, corners, iy + 1, prev)
        x += np.where(ix > 0, (1 - fy) * lo + fy * hi, 0.0)
        r0 = self._lookup(self.cond, corners, iy, self.w - 2)
        r1 = self._lookup(self.cond, corners, iy + 1, self.w - 2)
        with np.errstate(divide="ignore", invalid="ignore"):
            x = x / ((1 - fy) * r0 + fy * r1)
        y = fy * (r0 + (r1 - r0) * 0.5 * fy) / (self.h - 1)
        y += np.where(iy > 0, self._lookup(self.marg, corners, np.maximum(iy - 1, 0)), 0.0)
        if not self.normalized:
            y = y / self._lookup(self.marg, corners, self.h - 2)
        return np.stack([x, y], axis=1), pdf


def _sample_segment(u, inv_width, v0, v1):
    """Position t in [0, 1] where the integral of lerp(v0, v1) over [0, t] (a segment of
    width 1 / inv_width) reaches ``u``: the root of a quadratic, or linear when flat."""
    non_const = np.abs(v0 - v1) > 1e-4 * (v0 + v1)
    s = u * 2.0 * inv_width
    with np.errstate(invalid="ignore", divide="ignore"):
        quad = (v0 - np.sqrt(np.maximum(v0 * v0 + s * (v1 - v0), 0.0))) / (v0 - v1)
        lin = s / (v0 + v1)
    t = np.where(non_const, quad, lin)
    return np.where(np.isfinite(t), t, 0.0)
