"""Geometry builders: areas against closed forms, normals, uvs, the snake, transforms,
mesh files and parameter errors."""
import math

import numpy as np
import pytest
import trimesh

from bsdflab.render.curves import SNAKE_DEFAULTS
from bsdflab.render.geometry import GEOMETRY_TYPES, Mesh, build_mesh, mesh_area, triangle_normals, validate_mesh


def _area_convergence(spec_at, exact):
    """Areas at n, 2n, 4n: an inscribed tessellation is below the exact area, its error
    falls as 1/n^2, and Richardson extrapolation of that error recovers the closed form."""
    areas = [mesh_area(build_mesh(spec_at(n))) for n in (32, 64, 128)]
    errors = [exact - a for a in areas]
    assert all(e > 0 for e in errors)
    assert errors[0] / errors[1] == pytest.approx(4.0, rel=0.03)
    assert errors[1] / errors[2] == pytest.approx(4.0, rel=0.03)
    extrapolated = (4 * areas[2] - areas[1]) / 3
    assert extrapolated == pytest.approx(exact, rel=2e-6)


def test_sphere_area_converges_to_4_pi_r2():
    r = 1.7
    _area_convergence(lambda n: {"type": "sphere", "radius": r, "center": [1, 2, 3], "subdivisions": n},
                      4 * math.pi * r * r)


def test_torus_area_converges_to_4_pi2_R_r():
    R, r = 2.0, 0.6
    _area_convergence(lambda n: {"type": "torus", "major_radius": R, "minor_radius": r, "resolution": n,
                                 "minor_resolution": n // 2, "axis": [1, 1, 0]},
                      4 * math.pi**2 * R * r)


def test_sphere_normals_outward_and_uvs():
    c = np.array([0.5, -1.0, 2.0])
    m = build_mesh({"type": "sphere", "center": c.tolist(), "radius": 2.0, "subdivisions": 40})
    validate_mesh(m)
    d = m.positions - c
    assert np.allclose(np.linalg.norm(d, axis=1), 2.0)
    assert np.allclose(m.normals, d / 2.0)
    assert m.uvs.min() >= 0 and m.uvs.max() <= 1
    assert np.allclose(m.uvs[:, 1], np.arccos(np.clip(d[:, 1] / 2.0, -1, 1)) / np.pi)
    # u = phi / 2 pi away from the poles (and the seam column, where u = 1)
    body = (np.abs(d[:, 1]) < 1.99) & (m.uvs[:, 0] < 1)
    phi = np.mod(np.arctan2(-d[body, 2], d[body, 0]), 2 * np.pi)
    assert np.allclose(phi / (2 * np.pi), m.uvs[body, 0], atol=1e-9, rtol=0)
    # every triangle faces outward
    centroids = m.positions[m.indices].mean(axis=1)
    assert np.all(np.einsum("ij,ij->i", triangle_normals(m), centroids - c) > 0)


def test_torus_normals_point_away_from_the_core_circle():
    m = build_mesh({"type": "torus", "major_radius": 3.0, "minor_radius": 1.0, "resolution": 48})
    validate_mesh(m)
    p = m.positions
    radial = p * [1, 0, 1]
    core = 3.0 * radial / np.linalg.norm(radial, axis=1, keepdims=True)
    assert np.allclose(m.normals, p - core, atol=1e-9, rtol=0)
    assert m.uvs.min() >= 0 and m.uvs.max() <= 1


def test_rectangle_faces_its_normal_and_follows_up():
    m = build_mesh({"type": "rectangle", "center": [1, 2, 3], "normal": [0, 0, -2], "size": [4, 2],
                    "up": [0, 1, 0]})
    validate_mesh(m)
    assert mesh_area(m) == pytest.approx(8.0)
    n = triangle_normals(m)
    assert np.allclose(n / np.linalg.norm(n, axis=1, keepdims=True), [0, 0, -1])
    assert np.allclose(m.normals, [0, 0, -1])
    # v grows along up, u along up x normal's partner (t_u x t_v = normal)
    dv = m.positions[3] - m.positions[0]
    du = m.positions[1] - m.positions[0]
    assert np.allclose(dv, [0, 2, 0]) and np.allclose(du / 4, np.cross([0, 1, 0], [0, 0, -1]))
    assert sorted(map(tuple, m.uvs)) == [(0, 0), (0, 1), (1, 0), (1, 1)]


def test_disk_area_is_the_inscribed_polygon():
    n, r = 24, 1.5
    m = build_mesh({"type": "disk", "radius": r, "resolution": n, "normal": [1, 0, 0]})
    validate_mesh(m)
    assert mesh_area(m) == pytest.approx(0.5 * n * r * r * math.sin(2 * math.pi / n), rel=1e-12)


def _snake(**kw):
    return {"type": "snake_body", **SNAKE_DEFAULTS, **kw}


def test_snake_body_is_well_formed_and_rests_on_the_ground():
    spec = _snake(segments=400, sides=24)
    m = build_mesh(spec)
    validate_mesh(m)
    assert abs(m.positions[:, 1].min()) < 1e-9
    assert m.positions[:, 1].max() < 2.5 * spec["radius"]
    rows = m.positions.reshape(-1, 25, 3)
    uv = m.uvs.reshape(-1, 25, 2)
    # v: 0 .. 1 around, the seam column duplicated (same points, v = 0 and 1)
    assert np.allclose(uv[:, 0, 1], 0) and np.allclose(uv[:, -1, 1], 1)
    assert np.allclose(rows[:, 0], rows[:, -1])
    assert np.all(np.diff(uv[0, :, 1]) > 0)
    # u: constant per ring, strictly increasing, from 0 to the body length
    assert np.allclose(uv[:, :, 0], uv[:, :1, 0])
    u = uv[:, 0, 0]
    assert np.all(np.diff(u) > 0) and u[0] == 0 and u[-1] == pytest.approx(spec["length"])
    # u is arc length: the belly line (v = 0) runs right under the centreline
    belly = rows[:, 0]
    assert np.allclose(belly[:, 1], 0, atol=1e-9, rtol=0)
    arc = np.concatenate([[0], np.cumsum(np.linalg.norm(np.diff(belly, axis=0), axis=1))])
    assert np.allclose(arc, u, atol=2e-3 * spec["length"], rtol=0)
    # no twist: the top of every ring (v = 0.5) lies straight above its belly point
    top = rows[:, 12]
    assert np.allclose(top[:, [0, 2]], belly[:, [0, 2]], atol=1e-9, rtol=0)


def test_snake_radius_profile_tail_to_neck():
    spec = _snake(segments=400, sides=24)
    rows = build_mesh(spec).positions.reshape(-1, 25, 3)
    height = rows[:, 12, 1]   # top of each ring
    assert height[0] == pytest.approx(0, abs=1e-12)      # a closed, pointed tail
    assert height[-1] == pytest.approx(0, abs=1e-12)     # a closed front end (inside the head)
    mid = height[len(height) // 2]
    assert mid == pytest.approx((1 + 0.92 / spec["flatten"]) * spec["flatten"] * spec["radius"], rel=1e-6)
    neck = np.argmin(np.abs(np.linspace(0, 1, len(height)) - 0.97))
    assert height[neck] < 0.8 * mid


def test_snake_head_fits_the_body():
    body = build_mesh(_snake())
    head = build_mesh({**_snake(), "type": "snake_head"})
    validate_mesh(head)
    assert abs(head.positions[:, 1].min()) < 1e-9
    # the head starts inside the body's front end and continues its arc length
    assert head.uvs[:, 0].min() < body.uvs[:, 0].max() < head.uvs[:, 0].max()
    front = body.positions[np.argmax(body.uvs[:, 0])]
    assert np.linalg.norm(head.positions - front, axis=1).min() < SNAKE_DEFAULTS["neck_radius"]
    extent = np.ptp(head.positions, axis=0)
    assert SNAKE_DEFAULTS["head_length"] < max(extent[0], extent[2]) < 2 * SNAKE_DEFAULTS["head_length"]


def test_snake_heading_and_center_place_the_body():
    a = build_mesh(_snake(segments=200, sides=12, center=[0, 0]))
    b = build_mesh(_snake(segments=200, sides=12, center=[10, -5], heading_deg=90))
    rot = np.array([[0, 0, 1], [0, 1, 0], [-1, 0, 0]])   # +90 degrees about +Y: +X -> -Z
    assert np.allclose(a.positions @ rot.T + [10, 0, -5], b.positions, atol=1e-9, rtol=0)


def _rotation_scale_translation():
    c, s = math.cos(0.7), math.sin(0.7)
    rot = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]]) @ np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
    m = np.eye(4)
    m[:3, :3] = 2.0 * rot
    m[:3, 3] = [1, 2, 3]
    return m


def test_to_world_moves_positions_and_normals():
    spec = {"type": "sphere", "radius": 1.0, "subdivisions": 32}
    base = build_mesh(spec)
    m = _rotation_scale_translation()
    moved = build_mesh({**spec, "to_world": m.tolist()})
    validate_mesh(moved)
    assert mesh_area(moved) == pytest.approx(abs(np.linalg.det(m[:3, :3])) ** (2 / 3) * mesh_area(base))
    centre = np.array([1, 2, 3])
    assert np.allclose(moved.normals, (moved.positions - centre) / 2.0, atol=1e-12, rtol=0)


def test_to_world_area_scales_with_the_in_plane_determinant_and_mirroring_keeps_the_front():
    rect = {"type": "rectangle", "size": [1.0, 2.0]}
    m = np.diag([3.0, 7.0, -0.5, 1.0])   # mirrors z
    moved = build_mesh({**rect, "to_world": m.tolist()})
    validate_mesh(moved)
    assert mesh_area(moved) == pytest.approx(2.0 * 3.0 * 0.5)
    assert np.allclose(moved.normals, [0, 1, 0])
    n = triangle_normals(moved)
    assert np.all(n[:, 1] > 0)


def test_mesh_file_round_trip(tmp_path):
    ico = trimesh.creation.icosphere(subdivisions=2, radius=1.5)
    ico.export(tmp_path / "ico.obj")
    m = build_mesh({"type": "mesh", "path": "ico.obj"}, base_dir=str(tmp_path))
    validate_mesh(m)
    assert mesh_area(m) == pytest.approx(ico.area, rel=1e-6)
    assert len(m.indices) == len(ico.faces)
    assert np.all(np.einsum("ij,ij->i", m.normals, m.positions) > 0)
    flat = build_mesh({"type": "mesh", "path": str(tmp_path / "ico.obj"), "smooth": False})
    assert flat.normals is None


@pytest.mark.parametrize("content", [None, "", "this is not a mesh\n", "v 0 0 0\nv 1 0 0\n"])
def test_bad_mesh_files_raise(tmp_path, content):
    path = tmp_path / "bad.obj"
    if content is not None:
        path.write_text(content)
    with pytest.raises(ValueError, match="bad.obj"):
        build_mesh({"type": "mesh", "path": "bad.obj"}, base_dir=str(tmp_path))


@pytest.mark.parametrize("spec, message", [
    ({"type": "cube"}, "known types: sphere"),
    ({"radius": 1}, "known types"),
    ({"type": "sphere", "radius": -1}, "radius"),
    ({"type": "sphere", "radius": 0}, "radius"),
    ({"type": "sphere", "radius": float("nan")}, "radius"),
    ({"type": "sphere", "center": [0, float("inf"), 0]}, "center"),
    ({"type": "sphere", "center": [0, 0]}, "center"),
    ({"type": "sphere", "subdivisions": 2}, "subdivisions"),
    ({"type": "sphere", "subdivisions": 10**6}, "subdivisions"),
    ({"type": "sphere", "subdivisions": 8.5}, "subdivisions"),
    ({"type": "sphere", "subdivisions": True}, "subdivisions"),
    ({"type": "sphere", "radius": "big"}, "radius"),
    ({"type": "sphere", "raduis": 1}, "raduis.*known: center, radius, subdivisions"),
    ({"type": "torus", "major_radius": 1, "minor_radius": 2}, "minor_radius"),
    ({"type": "torus", "axis": [0, 0, 0]}, "axis"),
    ({"type": "rectangle", "size": [1, -1]}, "size"),
    ({"type": "rectangle", "normal": [0, 1, 0], "up": [0, 2, 0]}, "parallel"),
    ({"type": "sphere", "to_world": [[1, 0, 0], [0, 1, 0]]}, "to_world"),
    ({"type": "sphere", "to_world": np.diag([1, 1, 0, 1]).tolist()}, "invertible"),
    ({"type": "sphere", "to_world": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [1, 0, 0, 1]]}, "affine"),
    ({"type": "snake_body", "length": 30}, "shorter than length"),
    ({"type": "snake_body", "flatten": 1.5}, "flatten"),
    ({"type": "snake_head", "sides": 3}, "sides"),
    ({"type": "mesh"}, "path"),
    ({"type": "mesh", "path": "x.obj", "smooth": "yes"}, "smooth"),
])
def test_bad_specs_raise(spec, message):
    with pytest.raises(ValueError, match=message):
        build_mesh(spec)


def test_error_names_the_type():
    with pytest.raises(ValueError, match="^torus: "):
        build_mesh({"type": "torus", "minor_radius": -1})


def test_validate_mesh_catches_broken_meshes():
    good = build_mesh({"type": "rectangle"})
    validate_mesh(good)
    broken = [
        Mesh(good.positions, np.array([[0, 1, 4]]), None, None),                       # index out of range
        Mesh(good.positions, np.array([[0, 1, 1], [0, 1, 2]]), None, None),            # zero area
        Mesh(good.positions * np.nan, good.indices, None, None),                      # not finite
        Mesh(good.positions, good.indices, good.normals * 2, None),                   # not unit
        Mesh(good.positions, good.indices, -good.normals, None),                      # wound against normals
        Mesh(good.positions, good.indices, None, good.uvs[:3]),                       # wrong uv count
    ]
    for mesh in broken:
        with pytest.raises(ValueError):
            validate_mesh(mesh)


def _signed_volume(mesh: Mesh) -> float:
    """Divergence theorem over the triangles: positive when a closed surface is wound
    outward (counter-clockwise seen from outside)."""
    p = mesh.positions[mesh.indices]
    return float(np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2])).sum() / 6)


def test_every_type_builds_with_defaults():
    """Each type's defaults are the documented ones (bsdflab/render/geometry.py's docstring)
    and build a valid, outward-wound mesh: sphere radius 1 at the origin (every vertex at
    distance 1; 64 x 32 segments: inscribed volume within 1 % of 4 pi / 3), torus 1 / 0.25
    about +Y (every vertex on the tube; volume within 3 % of 2 pi^2 R r^2), rectangle 1 x 1
    facing +Y, disk radius 1 as a 64-fan (area exactly 32 sin(pi / 32)), the snake on the
    ground, swaying by its amplitude plus at most its radius to each side.
    Mutations caught: a default changed (torus minor_radius 0.3, sphere subdivisions 32),
    a closed mesh wound inward (negative volume), the disk fan one triangle short."""
    for kind in GEOMETRY_TYPES:
        if kind != "mesh":
            validate_mesh(build_mesh({"type": kind}))
    sphere = build_mesh({"type": "sphere"})
    assert np.abs(np.linalg.norm(sphere.positions, axis=1) - 1).max() < 1e-12
    assert len(sphere.indices) == 2 * 64 * 32 - 2 * 64  # the pole rows are one triangle per segment
    assert 0.99 * 4 * math.pi / 3 < _signed_volume(sphere) < 4 * math.pi / 3
    torus = build_mesh({"type": "torus"})
    x, y, z = torus.positions.T
    assert np.abs(np.hypot(np.hypot(x, z) - 1.0, y) - 0.25).max() < 1e-12
    exact = 2 * math.pi**2 * 1.0 * 0.25**2
    assert 0.97 * exact < _signed_volume(torus) < exact
    rect = build_mesh({"type": "rectangle"})
    assert mesh_area(rect) == pytest.approx(1.0, abs=1e-14)
    assert np.allclose(triangle_normals(rect) / np.linalg.norm(triangle_normals(rect), axis=1)[:, None],
                       [0, 1, 0], atol=1e-14, rtol=0)
    assert np.allclose(np.ptp(rect.positions, axis=0), [1, 0, 1], atol=1e-14, rtol=0)
    disk = build_mesh({"type": "disk"})
    assert mesh_area(disk) == pytest.approx(32 * math.sin(math.pi / 32), abs=1e-12)
    assert np.all(triangle_normals(disk)[:, 1] > 0)
    body = build_mesh({"type": "snake_body"})
    assert body.positions[:, 1].min() == pytest.approx(0.0, abs=1e-9)
    amplitude, radius = SNAKE_DEFAULTS["amplitude"], SNAKE_DEFAULTS["radius"]
    assert amplitude < np.abs(body.positions[:, 2]).max() < amplitude + radius
    assert _signed_volume(body) > 0 and _signed_volume(build_mesh({"type": "snake_head"})) > 0
