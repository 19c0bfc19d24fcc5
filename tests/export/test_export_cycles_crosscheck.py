"""The exported .blend, rendered by Cycles, against the export report's prediction.

A smooth guanine film (1.83, 400 nm) on keratin (1.5515) is exported to Blender (fitted
for Cycles' own thin film); Blender runs the exported file's scene (constant white world,
orthographic camera, black body: transmission is dropped, as the report says). Two
comparisons on 4 x 4 pixel blocks within theta <= 42 deg (tests/support/cycles_spheres.py
explains the scene and why larger angles are left out):

1. the mapping: Cycles' pixels equal the fitted Cycles model at the fitted parameters
   (tolerance 0.003 + 4 sigma of the seed-to-seed scatter, as test_cycles_thin_film.py);
2. the error: Delta E00 between Cycles' pixels and bsdflab's exact film at each block's
   angle agrees with the report's map at the nominal thickness (interpolated linearly
   between its 5-degree rows) within 0.4 Delta E00: 0.003 of reflectance moves Delta E00 by
   up to ~0.3 at these dark colours, plus the interpolation; measured 0.28 per pixel
   (docs/export.md). Deterministic for a given bpy (the scene has almost no noise).
"""
from __future__ import annotations

import json

import numpy as np
import pytest

from bsdflab.reference.approximations.cycles import cycles_thin_film_rgb
from bsdflab.reference.approximations.study import delta_e00, exact_rgb
from support.cycles_spheres import blocks, pixel_cosines, render_spheres_seeds

SIZE, BLOCK = 48, 4


@pytest.fixture(scope="module")
def crosscheck(tmp_path_factory, film_blender_export):
    report, _ = film_blender_export
    folder = tmp_path_factory.mktemp("cycles")
    p = {k: v["value"] for k, v in report["parameters"].items()}
    renders = list(render_spheres_seeds(p, [p["film_thickness_nm"]], str(folder), SIZE, seeds=(0, 1))[:, 0])
    return report, p, renders


def _blocks(img):
    return blocks(img, BLOCK)


def _region():
    cos = pixel_cosines(SIZE)
    keep = np.isfinite(cos) & (np.nan_to_num(cos) >= np.cos(np.radians(42.0)))
    full = keep.reshape(SIZE // BLOCK, BLOCK, SIZE // BLOCK, BLOCK).all(axis=(1, 3))
    return np.nan_to_num(cos, nan=1.0), full


def test_cycles_renders_the_fitted_model(crosscheck):
    """Mutation: Thin Film IOR + 0.03 in the exported Cycles scene (export/blender.py) fails it."""
    report, p, (a, b) = crosscheck
    cos, full = _region()
    model = cycles_thin_film_rgb(1.0, p["film_ior"], p["base_ior"], p["film_thickness_nm"], cos)
    mean, sigma = 0.5 * (_blocks(a) + _blocks(b)), np.abs(_blocks(a) - _blocks(b)) / 2
    diff = np.abs(mean - _blocks(model))[full]
    assert np.all(diff <= 4 * sigma[full] + 0.003), diff.max()


def test_cycles_error_against_the_exact_film_is_the_reported_one(crosscheck):
    report, p, (a, b) = crosscheck
    cos, full = _region()
    block_cos = _blocks(cos[..., None])[..., 0][full]        # mean cos of each block's pixels
    cycles = _blocks(0.5 * (a + b))[full]
    exact = _blocks(exact_rgb(1.0, 1.83, 1.5515, 400.0, cos))[full]
    measured = delta_e00(cycles, exact)
    e = report["delta_e00"]
    mid = len(e["thickness_scales"]) // 2
    predicted = np.interp(np.degrees(np.arccos(block_cos)), e["angles_deg"], np.array(e["map"])[:, mid])
    assert np.all(np.abs(measured - predicted) <= 0.4), np.abs(measured - predicted).max()
    assert json.dumps(report)   # the report is plain JSON


SNAKE_PROBE = '''import sys, json
import bpy
bpy.ops.wm.open_mainfile(filepath=sys.argv[sys.argv.index("--") + 1])
s = bpy.data.scenes["snake"]
obj = s.objects["snake"]
bsdf = obj.data.materials[0].node_tree.nodes["Principled BSDF"]
print("PROBE" + json.dumps({"active": bpy.context.scene.name, "vertices": len(obj.data.vertices),
      "triangles": len(obj.data.polygons), "camera": list(s.camera.location),
      "film": bsdf.inputs["Thin Film Thickness"].default_value}))
'''


def test_the_blend_holds_the_snake_mesh(crosscheck, film_blender_export):
    """The .blend's scene "snake": the snake's mesh (bsdflab.export.snake_mesh), its camera,
    the exported material; the sphere stays the active (validation) scene."""
    from bsdflab.export.blender import run_bpy
    from bsdflab.export.snake_mesh import snake_mesh

    report, p, _ = crosscheck
    blend = [f for f in report["files"] if f.endswith(".blend")][0]
    path = film_blender_export[1] / blend
    out = run_bpy(SNAKE_PROBE, [str(path)])
    got = json.loads(out.split("PROBE", 1)[1].splitlines()[0])
    want = snake_mesh()
    assert got["active"] == "Scene"
    assert (got["vertices"], got["triangles"]) == (len(want["positions"]), len(want["indices"]))
    np.testing.assert_allclose(got["camera"], want["camera_origin"], rtol=0, atol=1e-4)
    assert abs(got["film"] - p["film_thickness_nm"]) < 1e-3
