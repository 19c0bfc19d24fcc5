"""Procedural scenes, the registry and scene files."""
import json
import math

import numpy as np
import pytest
import trimesh

from bsdflab.bsdfs import from_dict
from bsdflab.presets import FILM_THICKNESS_NM
from bsdflab.reference.mitsuba_bsdf import to_mitsuba
from bsdflab.render import Scene
from bsdflab.render.textures import ScaleTexture
from bsdflab.scenes import SCENES, build_mesh, load_scene, save_scene, scene, validate_mesh
from bsdflab.scenes.appearance_grid import appearance_grid
from bsdflab.scenes.objects import VARIANTS, ablation_row
from bsdflab.tables import TableGrid

SCALE_KEYS = {"scales_per_unit_u", "scales_around", "gap", "jitter", "dome", "tilt_deg", "thickness_jitter",
              "seed", "periodic_v"}


def _check_bsdf(d):
    if d["type"] == "tabulated":
        assert set(d) <= {"type", "model", "grid", "rel_error", "min_samples"}
        from_dict(d["model"])
        TableGrid.from_dict(d["grid"])
    else:
        from_dict(d)


def _project(camera, points):
    """Normalised image coordinates (|x|, |y| <= 1 inside the frame) and depth."""
    o = np.asarray(camera.origin)
    f = np.subtract(camera.target, o)
    f /= np.linalg.norm(f)
    right = np.cross(f, camera.up)
    right /= np.linalg.norm(right)
    up = np.cross(right, f)
    d = points - o
    depth = d @ f
    tan_x = math.tan(math.radians(camera.fov_deg) / 2)
    tan_y = tan_x * camera.height / camera.width
    return (d @ right) / depth / tan_x, (d @ up) / depth / tan_y, depth


@pytest.mark.parametrize("name", list(SCENES))
def test_registry_scene_builds_and_validates(name):
    s = scene(name, width=32, height=24)
    assert isinstance(s, Scene) and (s.camera.width, s.camera.height) == (32, 24)
    for shape in s.shapes:
        validate_mesh(build_mesh(shape.geometry))
    for material in s.materials.values():
        _check_bsdf(material.bsdf)
        if material.gap_bsdf is not None:
            _check_bsdf(material.gap_bsdf)
        if material.scales is not None:
            assert set(material.scales) == SCALE_KEYS
            ScaleTexture.from_dict(material.scales)


@pytest.mark.parametrize("name", list(SCENES))
def test_registry_scene_round_trips_through_a_file(name, tmp_path):
    s = scene(name)
    path = save_scene(s, tmp_path / f"{name}.json")
    assert load_scene(path) == s
    d = json.loads((tmp_path / f"{name}.json").read_text())
    assert d["format"] == "bsdflab-scene" and d["version"] == 1


def test_unknown_scene_and_option():
    with pytest.raises(ValueError, match="known scenes: snake, sphere, torus"):
        scene("snak")
    with pytest.raises(ValueError, match="snake"):
        scene("snake", colour="red")


def test_snake_scene_materials_and_framing():
    s = scene("snake")
    skin = s.materials["skin"]
    assert skin.bsdf["type"] == "tabulated" and skin.bsdf["model"]["type"] == "layered"
    nodes = skin.bsdf["grid"]["thickness_nm"]
    jitter = skin.scales["thickness_jitter"]
    assert nodes[0] <= FILM_THICKNESS_NM * (1 - jitter) and nodes[-1] >= FILM_THICKNESS_NM * (1 + jitter)
    assert skin.gap_bsdf == {"type": "diffuse", "reflectance": [0.02, 0.018, 0.016]}
    assert s.environment.type == "sky" and any(sh.emission for sh in s.shapes)
    body = build_mesh(next(sh for sh in s.shapes if sh.name == "body").geometry)
    head = build_mesh(next(sh for sh in s.shapes if sh.name == "head").geometry)
    assert abs(body.positions[:, 1].min()) < 1e-9
    # the whole animal is in the frame, and it fills a good part of it
    pts = np.concatenate([body.positions, head.positions])
    x, y, depth = _project(s.camera, pts)
    assert np.all(depth > 0) and np.abs(x).max() < 0.98 and np.abs(y).max() < 0.98
    assert np.ptp(x) > 1.2
    # the light is above the ground and faces the snake
    light = next(sh for sh in s.shapes if sh.emission)
    to_snake = pts.mean(axis=0) - np.asarray(light.geometry["center"])
    assert light.geometry["center"][1] > 0 and np.dot(light.geometry["normal"], to_snake) > 0


def test_snake_material_choices():
    assert scene("snake", material="direct").materials["skin"].bsdf["type"] == "layered"
    assert scene("snake", material="xenopeltis-diffuse").materials["skin"].bsdf["type"] == "diffuse"
    assert scene("snake", material="xenopeltis-stack").materials["skin"].bsdf["type"] == "tabulated"
    assert scene("snake", scales=False).materials["skin"].scales is None
    with pytest.raises(ValueError, match="table, direct, xenopeltis"):
        scene("snake", material="glass")


def test_ablation_row_variants():
    row = ablation_row("torus")
    assert [label for label, _ in row] == list(VARIANTS)
    mats = [s.materials["object"] for _, s in row]
    assert mats[0].scales is None and mats[0].bsdf["type"] == "diffuse"
    assert mats[1].scales is not None and mats[1].gap_bsdf is None and mats[1].bsdf == mats[0].bsdf
    assert mats[2].bsdf["type"] == "tabulated" and mats[2].bsdf["model"]["slabs"][0]["thickness_um"] == 0
    assert mats[3].gap_bsdf is not None and mats[3].bsdf["model"]["slabs"][0]["thickness_um"] > 0
    assert scene("sphere", variant="full", material="direct").materials["object"].bsdf["type"] == "layered"
    with pytest.raises(ValueError, match="variant"):
        scene("sphere", variant="shiny")


def test_object_scales_fit_the_uv_periods():
    for name in ("sphere", "torus"):
        scales = scene(name).materials["object"].scales
        rows = scales["scales_per_unit_u"]
        assert rows == int(rows) and int(rows) % 2 == 0   # u wraps: a whole, even number of rows
    assert scene("sphere").materials["object"].scales["periodic_v"] is False   # pole to pole
    assert scene("torus").materials["object"].scales["periodic_v"] is True


def test_objects_rest_on_the_ground():
    for name in ("sphere", "torus", "appearance-grid"):
        s = scene(name)
        obj = next(sh for sh in s.shapes if sh.material not in (None, "ground"))
        assert build_mesh(obj.geometry).positions[:, 1].min() == pytest.approx(0, abs=1e-9)


def test_appearance_grid_cells():
    grid = appearance_grid()
    assert len(grid) == 6
    films = {(m["film"][0]["thickness_nm"], m["eta"]) for m in (s.materials["film"].bsdf for _, s in grid)}
    assert films == {(t, n) for t in (300.0, 600.0, 1200.0) for n in (1.0, 2.0)}
    # interior index 1.0 vs 2.0 changes the film's colour at the same thickness
    wi = np.array([0.3, 0.0, 0.954])
    wo = wi * [-1, -1, 1]
    a = from_dict(scene("appearance-grid", thickness_nm=600.0, interior_ior=1.0).materials["film"].bsdf).eval(wi, wo)
    b = from_dict(scene("appearance-grid", thickness_nm=600.0, interior_ior=2.0).materials["film"].bsdf).eval(wi, wo)
    assert np.abs(a / a.sum() - b / b.sum()).max() > 0.05


def test_furnace_and_basic_materials():
    f = scene("furnace")
    assert f.environment.type == "constant" and f.environment.radiance == (1.0, 1.0, 1.0)
    assert len(f.shapes) == 1 and f.materials["white"].bsdf["reflectance"] == 1.0 and f.max_depth >= 32
    b = scene("basic-materials")
    assert (b.camera.width, b.camera.height, b.max_depth) == (64, 48, 6)
    kinds = {m.bsdf["type"] for m in b.materials.values()}
    assert kinds == {"diffuse", "conductor", "roughconductor", "dielectric", "roughdielectric"}
    assert scene("basic-materials", max_depth=3, environment=False).environment.type == "none"


def test_basic_materials_have_mitsuba_counterparts():
    for name, material in scene("basic-materials").materials.items():
        assert to_mitsuba(material.bsdf)["type"] in {"diffuse", "conductor", "roughconductor", "dielectric",
                                                     "roughdielectric"}, name


# -- scene files ------------------------------------------------------------------------------
def _write(tmp_path, text, name="scene.json"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_corrupted_json_names_line_and_column(tmp_path):
    text = json.dumps({"format": "bsdflab-scene", "version": 1, **scene("furnace").to_dict()}, indent=1)
    path = _write(tmp_path, text.replace('"camera": {', '"camera": {,', 1))
    with pytest.raises(ValueError, match=r"line \d+, column \d+"):
        load_scene(path)


@pytest.mark.parametrize("change, message", [
    ({"format": "mitsuba"}, "not a bsdflab scene file"),
    ({"format": None}, "not a bsdflab scene file"),
    ({"version": 2}, "version 2"),
    ({"lamps": []}, "unknown scene keys: lamps"),
    ({"lights": [{"type": "point", "intensity": 1}]}, "position is required"),
    ({"max_depth": 0}, "max_depth"),
])
def test_bad_scene_files(tmp_path, change, message):
    d = {"format": "bsdflab-scene", "version": 1, **scene("furnace").to_dict(), **change}
    d = {k: v for k, v in d.items() if v is not None}
    with pytest.raises(ValueError, match=message):
        load_scene(_write(tmp_path, json.dumps(d)))


def test_unreadable_and_non_object_files(tmp_path):
    with pytest.raises(ValueError, match="cannot read"):
        load_scene(tmp_path / "missing.json")
    with pytest.raises(ValueError, match="not a bsdflab scene file"):
        load_scene(_write(tmp_path, "[1, 2, 3]"))
    binary = tmp_path / "binary.json"
    binary.write_bytes(b"\xff\xfe\x00")
    with pytest.raises(ValueError, match="cannot read"):
        load_scene(binary)


def test_unknown_geometry_type_in_a_file(tmp_path):
    d = {"format": "bsdflab-scene", "version": 1, **scene("furnace").to_dict()}
    d["shapes"][0]["geometry"]["type"] = "cube"
    with pytest.raises(ValueError, match="unknown geometry type 'cube'"):
        load_scene(_write(tmp_path, json.dumps(d)))


def test_relative_paths_resolve_against_the_file(tmp_path):
    folder = tmp_path / "scenes"
    folder.mkdir()
    trimesh.creation.icosphere(subdivisions=1).export(folder / "blob.obj")
    d = scene("furnace").to_dict()
    d["shapes"][0]["geometry"] = {"type": "mesh", "path": "blob.obj"}
    d["environment"] = {"type": "envmap", "path": "sky.exr"}
    path = _write(folder, json.dumps({"format": "bsdflab-scene", "version": 1, **d}))
    s = load_scene(path)
    assert s.shapes[0].geometry["path"] == str(folder / "blob.obj")
    assert s.environment.path == str(folder / "sky.exr")
    validate_mesh(build_mesh(s.shapes[0].geometry))


def test_save_is_atomic_and_leaves_no_temporary_files(tmp_path):
    path = save_scene(scene("furnace"), tmp_path / "out" / "f.json")
    assert [p.name for p in (tmp_path / "out").iterdir()] == ["f.json"]
    assert load_scene(path) == scene("furnace")
    with pytest.raises(ValueError):
        save_scene({"not": "a scene"}, tmp_path / "g.json")
