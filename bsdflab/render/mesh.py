"""The mesh type and the building blocks every mesh generator shares: the parameter
reader of geometry specs, quad-grid triangulation, in-plane axes and normalisation.

A leaf module: `geometry` (the primitives and `build_mesh`) and `curves` (the snake)
both build on it, and neither imports the other's internals through it.
"""
from __future__ import annotations

import contextlib
import contextvars
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from bsdflab.util import limits
from bsdflab.util.args import brief

MAX_SEGMENTS = 4096


@dataclass(frozen=True)
class Mesh:
    positions: np.ndarray            # (V, 3) float64, world space
    indices: np.ndarray              # (F, 3) int64, counter-clockwise seen from the front
    normals: np.ndarray | None       # (V, 3) unit shading normals (front side) or None
    uvs: np.ndarray | None           # (V, 2) or None


# -- parameter checking ------------------------------------------------------------------
class Params:
    """Reads one spec's parameters, naming the type in every error."""

    def __init__(self, kind: str, spec: dict, known: dict[str, Any]):
        self.kind, self.spec, self.known = kind, spec, known
        unknown = set(spec) - set(known) - {"type", "to_world"}
        if unknown:
            raise ValueError(f"{kind}: unknown parameters {', '.join(sorted(unknown))}; "
                             f"known: {', '.join(sorted(known))}, to_world")

    def get(self, name: str) -> Any:
        return self.spec.get(name, self.known[name])

    def number(self, name: str, lo: float = -math.inf, hi: float = math.inf, positive: bool = False) -> float:
        value = self.get(name)
        try:
            v = float(value)
        except (TypeError, ValueError, OverflowError):
            raise ValueError(f"{self.kind}: {name} must be a finite number, got {brief(value)}") from None
        if isinstance(value, bool) or not math.isfinite(v) or not lo <= v <= hi or (positive and v <= 0):
            bound = "> 0" if positive else f"in [{lo}, {hi}]"
            raise ValueError(f"{self.kind}: {name} must be a finite number {bound}, got {brief(value)}")
        return v

    def integer(self, name: str, lo: int, hi: int) -> int:
        value = self.get(name)
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not lo <= value <= hi:
            raise ValueError(f"{self.kind}: {name} must be an integer in [{lo}, {hi}], got {brief(value)}")
        return int(value)

    def vector(self, name: str, n: int = 3, unit: bool = False, positive: bool = False) -> np.ndarray:
        value = self.get(name)
        try:
            a = np.asarray(value, dtype=float)
        except (TypeError, ValueError, OverflowError):
            a = np.empty(0)
        if a.shape != (n,) or not np.all(np.isfinite(a)):
            raise ValueError(f"{self.kind}: {name} must be {n} finite numbers, got {brief(value)}")
        if positive and np.any(a <= 0):
            raise ValueError(f"{self.kind}: {name} must be > 0, got {brief(value)}")
        if unit:
            length = np.linalg.norm(a)
            if length == 0:
                raise ValueError(f"{self.kind}: {name} must not be zero")
            a = a / length
        return a

    def flag(self, name: str) -> bool:
        value = self.get(name)
        if not isinstance(value, bool):
            raise ValueError(f"{self.kind}: {name} must be true or false, got {brief(value)}")
        return value


class Sized(Exception):
    """Raised by `reserve` while sizing (``sizing()``): the builder stops at its size check."""

    def __init__(self, vertices: int, triangles: int):
        super().__init__(f"{vertices} vertices, {triangles} triangles")
        self.vertices, self.triangles = int(vertices), int(triangles)


_SIZING = contextvars.ContextVar("bsdflab_mesh_sizing", default=False)


@contextlib.contextmanager
def sizing():
    """Within this block a mesh builder validates its parameters and checks its size, then
    raises `Sized` instead of allocating (a server sizes a render before admitting it)."""
    token = _SIZING.set(True)
    try:
        yield
    finally:
        _SIZING.reset(token)


def reserve(kind: str, vertices: int, triangles: int) -> None:
    """Refuse a mesh whose size would exceed the caps, before building it (bsdflab.util.limits)."""
    limits.check_count(f"{kind}: triangles", int(triangles), "BSDFLAB_MAX_TRIANGLES")
    limits.check_bytes(f"{kind} mesh ({int(vertices)} vertices, {int(triangles)} triangles)",
                       limits.mesh_bytes(vertices, triangles))
    if _SIZING.get():
        raise Sized(vertices, triangles)


# -- shared construction helpers -----------------------------------------------------------
def grid_indices(rows: int, cols: int, flip: bool = False, collapsed_first: bool = False,
                 collapsed_last: bool = False) -> np.ndarray:
    """Triangles over a (rows+1) x (cols+1) vertex grid (row-major). Each quad gives two
    triangles whose normal follows d(row) x d(col) (reversed with ``flip``); a collapsed
    first/last row (all its vertices at one point, e.g. a pole) gives one triangle per
    quad, so no triangle has zero area."""
    i, j = np.meshgrid(np.arange(rows), np.arange(cols), indexing="ij")
    a = i * (cols + 1) + j
    b, d = a + 1, a + cols + 1
    c = d + 1
    lower = np.stack([a, d, c], axis=-1)   # degenerate when row i + 1 is collapsed
    upper = np.stack([a, c, b], axis=-1)   # degenerate when row i is collapsed
    keep_lower = np.ones((rows, cols), bool)
    keep_upper = np.ones((rows, cols), bool)
    if collapsed_first:
        keep_upper[0] = False
    if collapsed_last:
        keep_lower[-1] = False
    tris = np.concatenate([lower[keep_lower], upper[keep_upper]])
    if flip:
        tris = tris[:, ::-1]
    return tris.astype(np.int64)


def plane_axes(normal: np.ndarray, up: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    """In-plane axes (t_u, t_v) with t_u x t_v = normal; t_v follows ``up``."""
    if up is None:
        up = np.array([0.0, 0.0, -1.0]) if abs(normal[1]) > 0.999 else np.array([0.0, 1.0, 0.0])
    t_v = up - np.dot(up, normal) * normal
    length = np.linalg.norm(t_v)
    if length < 1e-9:
        raise ValueError("up must not be parallel to the normal")
    t_v /= length
    return np.cross(t_v, normal), t_v


def normalise(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)
