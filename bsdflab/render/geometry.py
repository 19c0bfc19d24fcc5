"""Triangle meshes from geometry specs (``Shape.geometry`` dicts).

``build_mesh({"type": ..., parameters}, base_dir)`` returns a ``Mesh`` in world space.
Every type takes an optional ``"to_world"`` (a 4x4 affine matrix as nested lists) applied
after the type's own placement. Types and parameters (lengths in scene units):

- ``sphere``: center [0, 0, 0], radius 1, subdivisions 64 (segments around; half as many
  from pole to pole). UV sphere about +Y: u = phi / 2 pi, v = theta / pi (theta from +Y).
- ``torus``: center, major_radius 1, minor_radius 0.25, axis [0, 1, 0], resolution 64
  (segments around the axis), minor_resolution (segments around the tube; default
  in proportion to the radii, at least 8). u = angle about the axis / 2 pi, v = angle
  around the tube / 2 pi.
- ``rectangle``: center, normal [0, 1, 0] (the front, emitting side), size [1, 1],
  up (the in-plane direction of +v; default +Y, or -Z when the normal is vertical).
  Two triangles, uv in [0, 1]^2.
- ``disk``: center, normal, radius 1, resolution 64 (a fan); uv = (0.5, 0.5) + the
  in-plane position / (2 radius), oriented like the rectangle.
- ``snake_body``, ``snake_head``: see ``bsdflab.render.curves`` (SNAKE_DEFAULTS).
- ``mesh``: path (OBJ/PLY/STL, relative to ``base_dir``), smooth (True: per-vertex
  normals from the file or area-weighted; False: flat shading).

Meshes are wound counter-clockwise seen from the front, and shading normals point to
the front (outward for closed surfaces).
"""
from __future__ import annotations

import os
from collections.abc import Callable
from typing import Any

import numpy as np

from bsdflab.render.curves import SNAKE_DEFAULTS, snake_body, snake_head, snake_layout
from bsdflab.render.mesh import MAX_SEGMENTS, Mesh, Sized, grid_indices, reserve, sizing
from bsdflab.render.mesh import Params as _Params
from bsdflab.render.mesh import normalise as _normalise
from bsdflab.render.mesh import plane_axes as _orthonormal
from bsdflab.util import limits
from bsdflab.util.args import brief

__all__ = ["GEOMETRY_TYPES", "MAX_SEGMENTS", "Mesh", "build_mesh", "grid_indices", "mesh_area", "mesh_size",
           "transform_mesh", "triangle_normals", "validate_mesh"]

# -- primitives --------------------------------------------------------------------------
def _sphere(p: _Params) -> Mesh:
    center = p.vector("center")
    radius = p.number("radius", positive=True)
    n_phi = p.integer("subdivisions", 4, MAX_SEGMENTS)
    n_theta = max(2, n_phi // 2)
    reserve(p.kind, (n_theta + 1) * (n_phi + 1), 2 * n_theta * n_phi)
    theta = np.linspace(0.0, np.pi, n_theta + 1)
    phi = np.linspace(0.0, 2 * np.pi, n_phi + 1)
    th, ph = np.meshgrid(theta, phi, indexing="ij")
    # z = -sin(theta) sin(phi) makes d(theta) x d(phi) point outward
    n = np.stack([np.sin(th) * np.cos(ph), np.cos(th), -np.sin(th) * np.sin(ph)], axis=-1)
    n[0, :] = (0.0, 1.0, 0.0)   # exact poles
    n[-1, :] = (0.0, -1.0, 0.0)
    u = ph / (2 * np.pi)
    u[[0, -1], :-1] += 0.5 / n_phi   # a pole vertex's u is the middle of its triangle
    uv = np.stack([u, th / np.pi], axis=-1)
    return Mesh(center + radius * n.reshape(-1, 3),
                grid_indices(n_theta, n_phi, collapsed_first=True, collapsed_last=True),
                n.reshape(-1, 3), uv.reshape(-1, 2))


def _torus(p: _Params) -> Mesh:
    center = p.vector("center")
    major = p.number("major_radius", positive=True)
    minor = p.number("minor_radius", positive=True)
    if minor >= major:
        raise ValueError(f"torus: minor_radius ({minor}) must be smaller than major_radius ({major})")
    axis = p.vector("axis", unit=True)
    n_major = p.integer("resolution", 3, MAX_SEGMENTS)
    if p.get("minor_resolution") is None:
        n_minor = min(MAX_SEGMENTS, max(8, round(n_major * minor / major)))
    else:
        n_minor = p.integer("minor_resolution", 3, MAX_SEGMENTS)
    reserve(p.kind, (n_minor + 1) * (n_major + 1), 2 * n_minor * n_major)
    e1, e2 = _orthonormal(axis, None)   # e1 x e2 = axis
    psi = np.linspace(0.0, 2 * np.pi, n_minor + 1)      # around the tube: rows
    phi = np.linspace(0.0, 2 * np.pi, n_major + 1)      # around the axis: columns
    ps, ph = np.meshgrid(psi, phi, indexing="ij")
    radial = np.cos(ph)[..., None] * e1 + np.sin(ph)[..., None] * e2
    n = np.cos(ps)[..., None] * radial + np.sin(ps)[..., None] * axis
    pos = center + major * radial + minor * n
    uv = np.stack([ph / (2 * np.pi), ps / (2 * np.pi)], axis=-1)
    # d(psi) x d(phi) points into the tube for a right-handed (e1, e2, axis)
    return Mesh(pos.reshape(-1, 3), grid_indices(n_minor, n_major, flip=True),
                n.reshape(-1, 3), uv.reshape(-1, 2))


def _plane_axes(p: _Params) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    normal = p.vector("normal", unit=True)
    up = None if p.get("up") is None else p.vector("up", unit=True)
    try:
        t_u, t_v = _orthonormal(normal, up)
    except ValueError as e:
        raise ValueError(f"{p.kind}: {e}") from None
    return normal, t_u, t_v


def _rectangle(p: _Params) -> Mesh:
    center = p.vector("center")
    normal, t_u, t_v = _plane_axes(p)
    w, h = p.vector("size", 2, positive=True)
    uv = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    pos = center + (uv[:, :1] - 0.5) * w * t_u + (uv[:, 1:] - 0.5) * h * t_v
    return Mesh(pos, np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int64), np.tile(normal, (4, 1)), uv)


def _disk(p: _Params) -> Mesh:
    center = p.vector("center")
    normal, t_u, t_v = _plane_axes(p)
    radius = p.number("radius", positive=True)
    n = p.integer("resolution", 3, 65536)
    reserve(p.kind, n + 1, n)
    a = np.arange(n) * (2 * np.pi / n)
    ring = np.stack([np.cos(a), np.sin(a)], axis=-1)
    local = np.concatenate([[[0.0, 0.0]], ring])
    pos = center + radius * (local[:, :1] * t_u + local[:, 1:] * t_v)
    k = np.arange(n)
    tris = np.stack([np.zeros(n, np.int64), 1 + k, 1 + (k + 1) % n], axis=-1)
    return Mesh(pos, tris, np.tile(normal, (n + 1, 1)), 0.5 + 0.5 * local)


def _mesh_file(p: _Params, base_dir: str | None) -> Mesh:
    import trimesh

    path = p.get("path")
    if not isinstance(path, str) or not path:
        raise ValueError(f"mesh: path must be a file name, got {path!r}")
    smooth = p.flag("smooth")
    full = path if base_dir is None or os.path.isabs(path) else os.path.join(base_dir, path)
    if not os.path.isfile(full):
        raise ValueError(f"mesh: cannot read {full}: {'not a file' if os.path.exists(full) else 'no such file'}")
    limits.check_bytes(f"mesh: {full}", limits.MESH_FILE_EXPANSION * os.path.getsize(full))
    try:
        loaded = trimesh.load(full, force="mesh", process=False)
    except Exception as e:   # trimesh raises many types for unreadable files
        raise ValueError(f"mesh: cannot read {full}: {type(e).__name__}: {e}") from None
    if not isinstance(loaded, trimesh.Trimesh) or len(loaded.faces) == 0:
        raise ValueError(f"mesh: {full} holds no triangles")
    positions = np.asarray(loaded.vertices, dtype=float)
    indices = np.asarray(loaded.faces, dtype=np.int64)
    # checked before anything indexes with them (trimesh's normals would raise IndexError)
    if indices.ndim != 2 or indices.shape[1] != 3:
        raise ValueError(f"mesh: {full} has faces of shape {indices.shape}, expected triangles")
    if len(positions) == 0 or indices.min() < 0 or indices.max() >= len(positions):
        raise ValueError(f"mesh: {full} has face indices outside [0, {len(positions) - 1}] "
                         f"(found {indices.min()} to {indices.max()})")
    if not np.all(np.isfinite(positions)):
        raise ValueError(f"mesh: {full} has vertex positions that are not finite")
    reserve(f"mesh: {full}", len(positions), len(indices))
    normals = None
    if smooth:
        try:
            normals = np.asarray(loaded.vertex_normals, dtype=float)
        except Exception as e:  # degenerate geometry inside trimesh
            raise ValueError(f"mesh: {full}: cannot compute vertex normals ({type(e).__name__}: {e})") from None
        bad = ~np.isfinite(normals).all(axis=1) | (np.linalg.norm(normals, axis=1) < 0.5)
        if bad.any():
            raise ValueError(f"mesh: {full} has {int(bad.sum())} vertices without a usable normal")
        normals = _normalise(normals)
    uv = getattr(loaded.visual, "uv", None)
    uvs = None if uv is None or len(uv) != len(positions) else np.asarray(uv, dtype=float)
    return Mesh(positions, indices, normals, uvs)


# -- transforms ----------------------------------------------------------------------------
def _matrix(kind: str, value: Any) -> np.ndarray:
    try:
        m = np.asarray(value, dtype=float)
    except (TypeError, ValueError, OverflowError):
        m = np.empty(0)
    if m.shape != (4, 4) or not np.all(np.isfinite(m)):
        raise ValueError(f"{kind}: to_world must be a 4x4 matrix of finite numbers, got {brief(value)}")
    if not np.allclose(m[3], [0, 0, 0, 1]):
        raise ValueError(f"{kind}: to_world must be affine (last row 0 0 0 1), got {m[3].tolist()}")
    if abs(np.linalg.det(m[:3, :3])) < 1e-12:
        raise ValueError(f"{kind}: to_world must be invertible")
    return m


def transform_mesh(mesh: Mesh, m: np.ndarray) -> Mesh:
    """``mesh`` under the affine 4x4 ``m``: normals by the inverse transpose; a mirroring
    transform reverses the winding so the front side stays where the normals point."""
    linear = m[:3, :3]
    positions = mesh.positions @ linear.T + m[:3, 3]
    normals = None
    if mesh.normals is not None:
        normals = _normalise(mesh.normals @ np.linalg.inv(linear))
    indices = mesh.indices[:, ::-1].copy() if np.linalg.det(linear) < 0 else mesh.indices
    return Mesh(positions, indices, normals, mesh.uvs)


# -- entry point ---------------------------------------------------------------------------
def _snake(kind: str) -> Callable[[_Params], Mesh]:
    def build(p: _Params) -> Mesh:
        layout = snake_layout(p)
        return snake_body(layout) if kind == "snake_body" else snake_head(layout)
    return build


def _snake_defaults() -> dict[str, Any]:
    return SNAKE_DEFAULTS


_ORIGIN = [0.0, 0.0, 0.0]
_Y = [0.0, 1.0, 0.0]
GEOMETRY_TYPES: dict[str, tuple[Callable[[], dict[str, Any]], Callable[..., Mesh]]] = {
    "sphere": (lambda: {"center": _ORIGIN, "radius": 1.0, "subdivisions": 64}, _sphere),
    "torus": (lambda: {"center": _ORIGIN, "major_radius": 1.0, "minor_radius": 0.25, "axis": _Y,
                       "resolution": 64, "minor_resolution": None}, _torus),
    "rectangle": (lambda: {"center": _ORIGIN, "normal": _Y, "size": [1.0, 1.0], "up": None}, _rectangle),
    "disk": (lambda: {"center": _ORIGIN, "normal": _Y, "radius": 1.0, "up": None, "resolution": 64}, _disk),
    "snake_body": (_snake_defaults, _snake("snake_body")),
    "snake_head": (_snake_defaults, _snake("snake_head")),
    "mesh": (lambda: {"path": None, "smooth": True}, _mesh_file),
}


def build_mesh(spec: dict, base_dir: str | None = None) -> Mesh:
    """The world-space mesh of a geometry spec; ValueError for unknown types or bad
    parameters (relative ``mesh`` paths are resolved against ``base_dir``)."""
    if not isinstance(spec, dict) or "type" not in spec:
        raise ValueError(f"a geometry spec must be a dict with a 'type'; known types: {', '.join(GEOMETRY_TYPES)}")
    kind = spec["type"]
    if not isinstance(kind, str) or kind not in GEOMETRY_TYPES:
        raise ValueError(f"unknown geometry type {kind!r}; known types: {', '.join(GEOMETRY_TYPES)}")
    defaults, build = GEOMETRY_TYPES[kind]
    params = _Params(kind, spec, defaults())
    mesh = build(params, base_dir) if kind == "mesh" else build(params)
    if spec.get("to_world") is not None:
        mesh = transform_mesh(mesh, _matrix(kind, spec["to_world"]))
    return mesh


def mesh_size(spec: dict, base_dir: str | None = None) -> tuple[int, int]:
    """(vertices, triangles) of ``build_mesh(spec)`` with its parameters validated and its
    size checked against the caps, without building a large mesh (the builder stops at its
    size check; the few fixed-size primitives are built, being tiny)."""
    with sizing():
        try:
            mesh = build_mesh(spec, base_dir)
        except Sized as e:
            return e.vertices, e.triangles
    return len(mesh.positions), len(mesh.indices)


# -- checks ----------------------------------------------------------------------------------
def triangle_normals(mesh: Mesh) -> np.ndarray:
    """Unnormalised geometric normals (length = twice the area), front side."""
    p = mesh.positions[mesh.indices]
    return np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])


def mesh_area(mesh: Mesh) -> float:
    return float(0.5 * np.linalg.norm(triangle_normals(mesh), axis=1).sum())


def validate_mesh(mesh: Mesh, check_orientation: bool = True) -> None:
    """Raise ValueError unless the mesh is well formed: shapes and dtypes, finite values,
    indices in range (and uint32-representable), no zero-area triangles, unit normals and,
    with ``check_orientation``, every triangle's winding agreeing with its vertex normals."""
    p, f = mesh.positions, mesh.indices
    if p.ndim != 2 or p.shape[1] != 3 or len(p) == 0:
        raise ValueError(f"positions must be (V, 3), got {p.shape}")
    if f.ndim != 2 or f.shape[1] != 3 or len(f) == 0 or not np.issubdtype(f.dtype, np.integer):
        raise ValueError(f"indices must be (F, 3) integers, got {f.shape} {f.dtype}")
    if len(p) >= 2**32:
        raise ValueError("too many vertices for 32-bit indices")
    if not np.all(np.isfinite(p)):
        raise ValueError("positions must be finite")
    if f.min() < 0 or f.max() >= len(p):
        raise ValueError(f"indices must lie in [0, {len(p) - 1}]")
    tn = triangle_normals(mesh)
    area2 = np.linalg.norm(tn, axis=1)
    scale = np.ptp(p, axis=0).max()
    tiny = area2 <= 1e-12 * scale**2
    if tiny.any():
        raise ValueError(f"{int(tiny.sum())} triangles have zero area (first: {int(np.argmax(tiny))})")
    for name, a, width in (("normals", mesh.normals, 3), ("uvs", mesh.uvs, 2)):
        if a is not None and (a.shape != (len(p), width) or not np.all(np.isfinite(a))):
            raise ValueError(f"{name} must be finite and ({len(p)}, {width}), got {a.shape}")
    if mesh.normals is not None:
        off = np.abs(np.linalg.norm(mesh.normals, axis=1) - 1)
        if off.max() > 1e-6:
            raise ValueError(f"normals must have unit length (worst: off by {off.max():.2e})")
        if check_orientation:
            agree = np.einsum("ij,ij->i", tn, mesh.normals[f].sum(axis=1))
            if np.any(agree <= 0):
                raise ValueError(f"{int((agree <= 0).sum())} triangles are wound against their normals")
