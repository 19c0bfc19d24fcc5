"""The Cycles thin-film model (bsdflab.reference.approximations.cycles, what the blender
export is fitted against) against real Cycles renders (bpy in its own interpreter, as the
blender export runs it; skipped where there is none). The scene is the export's: a smooth
Principled sphere, black base, IOR 1.5515, Thin Film IOR 1.83 at 250 / 400 / 1100 nm, a
constant white world, an orthographic camera, so a pixel holds F(n . view). The model under
test is ``{"model": rgb(n_outer, n_film, n_base, thickness_nm, cos), "render":
render_spheres}`` (images per seed, every seed in one bpy process): MaterialX's
Belcour-Barla model in the model's place must fail."""

from __future__ import annotations

import json
import os
import tempfile

import numpy as np

from bsdflab.validation.registry import REGISTRY, Outcome, SkipCheck, effort

SETTINGS = """
import os, json, math
cfg = json.loads(os.environ["CYCLES_CHECK_SPHERES"])
scene.render.resolution_x = scene.render.resolution_y = cfg["size"]
scene.cycles.samples = cfg["spp"]
scene.cycles.use_adaptive_sampling = False
scene.cycles.pixel_filter_type = "BOX"
scene.cycles.filter_width = cfg.get("filter_width", 0.01)
scene.render.threads_mode = "FIXED"
scene.render.threads = 2
"""
# every seed in one bpy process: a seed's images do not depend on the process (the same pixels
# to 6e-8), and a bpy process costs ~4 CPU-s of start and scene build against ~0.3 s a render
LOOP = (
    SETTINGS
    + """
for s in cfg["seeds"]:
    scene.cycles.seed = s
    for i, d in enumerate(cfg["thicknesses"]):
        bsdf.inputs["Thin Film Thickness"].default_value = d
        scene.render.filepath = os.path.join(cfg["folder"], f"sphere_{s}_{i}.exr")
        bpy.ops.render.render(write_still=True)
"""
)
PARAMS = {
    "base_color": (0.0, 0.0, 0.0),
    "roughness": 0.0,
    "base_ior": 1.5515,
    "film_ior": 1.83,
    "film_thickness_nm": 400.0,
}
THICKNESSES = (250.0, 400.0, 1100.0)
BLOCK, MAX_THETA_DEG, FLOOR = 4, 42.0, 0.003


def render_spheres(params: dict, thicknesses, folder: str, size: int = 48, spp: int = 4,
                   seeds=(0, 1)) -> np.ndarray:
    """Cycles images (S, T, size, size, 3) of the export's sphere for each seed and film
    thickness (nm), in one bpy process."""
    from bsdflab.export.blender import blender_script, run_bpy
    from bsdflab.render.image_io import read_exr

    cfg = {"size": size, "spp": spp, "seeds": [int(s) for s in seeds], "folder": folder,
           "thicknesses": [float(d) for d in thicknesses]}
    run_bpy(blender_script(params, "cycles-check") + LOOP, env=dict(os.environ, CYCLES_CHECK_SPHERES=json.dumps(cfg)))
    return np.stack([np.stack([read_exr(os.path.join(folder, f"sphere_{s}_{i}.exr"))[..., :3]
                               for i in range(len(thicknesses))]) for s in cfg["seeds"]])


def pixel_cosines(size: int) -> np.ndarray:
    """cos theta between the view direction and the sphere's normal at each pixel centre
    (size, size); NaN off the sphere."""
    c = (np.arange(size) + 0.5) / size * 2.0 - 1.0
    r2 = c[None, :] ** 2 + c[:, None] ** 2
    with np.errstate(invalid="ignore"):
        return np.where(r2 < 1.0, np.sqrt(1.0 - r2), np.nan)


def _blocks(img):
    t, h, w, c = img.shape
    return img.reshape(t, h // BLOCK, BLOCK, w // BLOCK, BLOCK, c).mean(axis=(2, 4))


def _cycles_model():
    from bsdflab.reference.approximations.cycles import cycles_thin_film_rgb

    return {"model": cycles_thin_film_rgb, "render": render_spheres}


@REGISTRY.check(
    name="export/cycles-model-vs-cycles",
    family="export",
    title="The Cycles thin-film model the blender export is fitted to, against real Cycles renders",
    model="bsdflab.reference.approximations.cycles.cycles_thin_film_rgb (Cycles' Principled thin film)",
    reference="Blender Cycles (bpy, CPU, 4 spp, 48 x 48, two seeds) of the exported sphere, black base, "
    "film 1.83 at 250 / 400 / 1100 nm on IOR 1.5515",
    statistic="share of 4 x 4 block-channel tests (sphere blocks within 42 deg) where |Cycles - model| "
    "exceeds its tolerance; the largest difference in the message",
    tolerance="0 failing tests; per test 4 sigma + 0.003, sigma the two seeds' scatter of the block mean "
    "(the scene is nearly deterministic), 0.003 for Cycles' float32 table (512 entries, linear "
    "interpolation) and the pixel footprint; alpha ~ 6e-5 per test (4 sigma), Sidak over ~200 "
    "tests ~ 0.01 (tests/export/test_cycles_thin_film.py)",
    effort=effort({"size": 48, "spp": 4}, {"size": 48, "spp": 4}),
    make_model=_cycles_model,
    seed=92,
)
def _cycles(ctx):
    from bsdflab.export.blender import blender_python

    render = ctx.model["render"]
    if render is render_spheres:
        try:
            blender_python()
        except ValueError as e:
            raise SkipCheck(str(e)) from None
    size, spp = int(ctx.effort["size"]), int(ctx.effort["spp"])
    with tempfile.TemporaryDirectory() as tmp:
        a, b = render(PARAMS, THICKNESSES, tmp, size, spp, seeds=(0, 1))
    cos = pixel_cosines(size)
    model = ctx.model["model"]
    predicted = np.stack([model(1.0, 1.83, 1.5515, d, np.nan_to_num(cos, nan=1.0)) for d in THICKNESSES])
    keep = np.isfinite(cos) & (np.nan_to_num(cos) >= np.cos(np.radians(MAX_THETA_DEG)))
    full = keep.reshape(size // BLOCK, BLOCK, size // BLOCK, BLOCK).all(axis=(1, 3))
    mean = 0.5 * (_blocks(a) + _blocks(b))
    sigma = np.abs(_blocks(a) - _blocks(b)) / 2.0
    diff = np.abs(mean - _blocks(predicted))[:, full]
    tol = 4.0 * sigma[:, full] + FLOOR
    share, worst = float(np.mean(diff > tol)), float(diff.max())
    return Outcome(
        share == 0.0 and diff.size > 100,
        share,
        0.0,
        "<=",
        f"{int(np.sum(diff > tol))} of {diff.size} block-channel tests beyond 4 sigma + {FLOOR}; "
        f"largest |Cycles - model| {worst:.4f}",
        {"tests": int(diff.size), "max_difference": worst},
    )
