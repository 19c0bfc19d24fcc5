"""Render smooth thin-film spheres with the real Blender Cycles (bpy, CPU) and predict them.

The scene is the Blender export's (``bsdflab.export.blender``): a unit sphere seen by an
orthographic camera (ortho scale 2) in a constant white world. With a black base and no
transmission, a pixel whose centre sees the sphere at normal n holds the specular
reflectance F(cos theta = n . view) times the world's radiance 1: the reflected ray
leaves the convex sphere and meets the world. The pixel filter is a box of 0.01 px, so a
pixel is its centre's value; what varies between seeds (the test's noise) is what is left.
"""
from __future__ import annotations

import json
import os

import numpy as np

from bsdflab.export.blender import blender_script, run_bpy
from bsdflab.validation.checks.cycles import (  # noqa: F401 -- the report's Cycles check's sphere, one implementation
    SETTINGS,
    pixel_cosines,
    render_spheres,
)

# the report's check renders every seed in one bpy process (~4 CPU-s a process saved)
render_spheres_seeds = render_spheres


# The same sphere seen in perspective, as both renderers' cameras can hold it: a pinhole at
# distance DIST on the axis, full field of view FOV_DEG (square image), pixels box-filtered.
DIST, FOV_DEG = 5.0, 26.0

PERSPECTIVE = SETTINGS + '''
cam.type = "PERSP"
cam.sensor_fit = "AUTO"
cam.angle = math.radians(cfg["fov"])
cam_obj.location = (0.0, -cfg["dist"], 0.0)
for s in cfg["seeds"]:
    scene.cycles.seed = s
    scene.render.filepath = os.path.join(cfg["folder"], f"persp_{s}.exr")
    bpy.ops.render.render(write_still=True)
'''


def render_perspective(params: dict, folder: str, size: int, spp: int, seeds=(0, 1)) -> np.ndarray:
    """Cycles images (len(seeds), size, size, 3) of the exported sphere in perspective."""
    from bsdflab.render.image_io import read_exr

    env = dict(os.environ, CYCLES_CHECK_SPHERES=json.dumps({"size": size, "spp": spp, "seeds": list(seeds),
                                                        "folder": folder, "fov": FOV_DEG, "dist": DIST,
                                                        "filter_width": 1.0}))
    run_bpy(blender_script(params, "cycles-persp") + PERSPECTIVE, env=env)
    return np.stack([read_exr(os.path.join(folder, f"persp_{s}.exr"))[..., :3] for s in seeds])


def bsdflab_sphere(bsdf: dict, size: int, spp: int, seed: int = 0):
    """bsdflab's render (RenderResult) of the same sphere with ``bsdf``, constant white world."""
    from bsdflab.render.render import render
    from bsdflab.render.scene import Camera, Environment, Material, Scene, Shape

    scene = Scene(Camera(origin=(0.0, 0.0, DIST), target=(0.0, 0.0, 0.0), up=(0.0, 1.0, 0.0), fov_deg=FOV_DEG,
                         width=size, height=size),
                  [Shape({"type": "sphere", "subdivisions": 256}, "m", name="sphere")], {"m": Material(bsdf)},
                  Environment(type="constant", radiance=(1.0, 1.0, 1.0)), max_depth=4)
    return render(scene, spp=spp, seed=seed, progress=False)


def perspective_cosines(size: int) -> np.ndarray:
    """cos theta between the ray and the sphere's normal at each pixel centre (NaN off it)."""
    t = np.tan(np.radians(FOV_DEG) / 2.0)
    c = ((np.arange(size) + 0.5) / size * 2.0 - 1.0) * t
    d = np.stack(np.broadcast_arrays(c[None, :], c[:, None], -np.ones((size, size))), axis=-1)
    d = d / np.linalg.norm(d, axis=-1, keepdims=True)
    o = np.array([0.0, 0.0, DIST])
    b = d @ o
    disc = b**2 - (o @ o - 1.0)
    with np.errstate(invalid="ignore"):
        hit = o - (b + np.sqrt(disc))[..., None] * d
        return np.where(disc > 0, -(hit * d).sum(-1), np.nan)


FILM = {"type": "dielectric", "int_ior": 1.5515, "ext_ior": 1.0, "film": [{"material": 1.83, "thickness_nm": 400.0}]}


def blocks(img: np.ndarray, block: int = 4) -> np.ndarray:
    """Means over block x block pixels, (H / block, W / block, C)."""
    h, w, c = img.shape
    return img.reshape(h // block, block, w // block, block, c).mean(axis=(1, 3))
