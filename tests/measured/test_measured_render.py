"""Image cross-check: the snake's table exported to RGL, rendered by Mitsuba 3 with its native
``measured`` plugin and by bsdflab's path tracer with ``bl.Measured`` on the same file;
per-pixel z-test at ALPHA = 1e-3 (Sidak over pixel-channels), as
tests/crosscheck/test_mitsuba_render.py. Both renderers read the same file, so any
disagreement is a reader's or a renderer's, not the export's."""
from __future__ import annotations

import os
from pathlib import Path

import pytest

from bsdflab.measured import export_table
from bsdflab.render import Camera, Environment, Material, Scene, Shape
from bsdflab.testing import image_z_test

pytestmark = pytest.mark.mitsuba

ALPHA = 1e-3
SNAKE_TABLE = {"grid": {"n_theta_i": 6, "n_theta_o": 12, "n_phi": 7, "thickness_nm": []},
               "rel_error": 0.05, "min_samples": 256}


def snake_rgl(folder: Path, cache_dir) -> Path:
    from bsdflab.presets import xenopeltis
    from bsdflab.render.build import resolve_bsdf

    table = resolve_bsdf({"type": "tabulated", "model": xenopeltis().to_dict(), **SNAKE_TABLE}, cache_dir=cache_dir)
    path = folder / "snake.bsdf"
    export_table(table, path, n_theta_i=8, resolution=24, error_points=2000)
    return path


def sphere(path: Path, width=32, height=24) -> Scene:
    return Scene(Camera(origin=(0.0, 1.4, 3.2), target=(0.0, 1.0, 0.0), fov_deg=45, width=width, height=height),
                 (Shape({"type": "sphere", "center": [0, 1, 0], "subdivisions": 32}, "snake", name="ball"),),
                 {"snake": Material({"type": "measured", "path": str(path)})},
                 Environment("sky", scale=2.0), max_depth=4, rr_depth=3)


def test_snake_rgl_renders_alike(tmp_path_factory, tmp_path):
    from bsdflab.reference.mitsuba_render import render_mitsuba
    from bsdflab.render.render import render

    folder = tmp_path_factory.mktemp("rgl")
    scene = sphere(snake_rgl(folder, tmp_path_factory.mktemp("tables")))
    ours = render(scene, spp=512, seed=0, progress=False)
    theirs = render_mitsuba(scene, 512, seed=1)
    result = image_z_test(ours.mean, ours.variance, *theirs, alpha=ALPHA)
    if not result.passed:
        png = result.plot(Path(os.environ.get("BSDFLAB_TEST_FIGURES", tmp_path)) / "snake-rgl.png",
                          title=result.summary(), labels=("bsdflab (bl.Measured)", "Mitsuba 3 (measured)"))
        pytest.fail(f"{result.summary()}\nfigure: {png}")


def test_lambertian_merl_renders_as_mitsuba_diffuse(tmp_path):
    """A hand-built MERL file holding a Lambertian BRDF (rho / pi), rendered by bsdflab through
    bl.Merl, against Mitsuba's own diffuse plugin with the same RGB albedo: an independent
    check of the MERL reader's scales and of its use in the renderer."""
    import numpy as np

    from bsdflab.measured.merl import DIMS, merl_bytes
    from bsdflab.reference.mitsuba_render import render_mitsuba
    from bsdflab.render.render import render

    rho = [0.2, 0.3, 0.4]
    path = tmp_path / "lambert.binary"
    path.write_bytes(merl_bytes(np.broadcast_to(np.array(rho)[:, None, None, None] / np.pi, (3, *DIMS))))
    scene = sphere(path)
    merl = Scene(scene.camera, scene.shapes, {"snake": Material({"type": "merl", "path": str(path)})},
                 scene.environment, max_depth=4, rr_depth=3)
    diffuse = Scene(scene.camera, scene.shapes,
                    {"snake": Material({"type": "diffuse", "reflectance": {"type": "rgb", "rgb": rho}})},
                    scene.environment, max_depth=4, rr_depth=3)
    ours = render(merl, spp=256, seed=0, progress=False)
    theirs = render_mitsuba(diffuse, 256, seed=1)
    # 4 x 4 blocks: power against a 3 % albedo error (a file 3 % too bright fails: 14 of 144
    # block-channels rejected), which single pixels at 256 spp do not have.
    result = image_z_test(ours.mean, ours.variance, *theirs, alpha=ALPHA, block=4)
    assert result.passed, result.summary()
