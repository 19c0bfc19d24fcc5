"""Small sphere renders of posterior draws (the in-package path tracer, direct PFMC
evaluation of each draw's material; kept small: a preview, not a reference image)."""
from __future__ import annotations

import numpy as np

from bsdflab.fit.material import material_dict
from bsdflab.render import Material, Scene, Shape, render
from bsdflab.scenes.snake import ground, ground_material, orbit_camera, sky, soft_box

SPHERE_RADIUS = 10.0
PREVIEW_WALKS = 16   # PFMC walks per BSDF evaluation in the preview renders


def sphere_scene(values, size: int, model=None) -> Scene:
    centre = [0.0, SPHERE_RADIUS, 0.0]
    shapes = (ground(), Shape({"type": "sphere", "center": centre, "radius": SPHERE_RADIUS, "subdivisions": 96},
                              material="object", name="sphere"),
              soft_box([-35.0, 70.0, -30.0], centre, 40.0, (14.0, 13.3, 12.4)))
    materials = {"ground": ground_material(), "object": Material(material_dict(values, PREVIEW_WALKS, model))}
    camera = orbit_camera(centre, 48.0, 25.0, 30.0, 40.0, size, size)
    return Scene(camera, shapes, materials, sky(), max_depth=4, name="fit-draw")


def render_draws(values: list[np.ndarray], labels: list[str], size: int, spp: int,
                 seed: int, model=None, progress: bool = False) -> list[tuple[str, np.ndarray]]:
    pairs = list(zip(values, labels))
    if progress:
        from tqdm import tqdm

        pairs = tqdm(pairs, desc="renders", unit="render", leave=False)
    return [(label, render(sphere_scene(v, size, model), spp=spp, seed=seed, progress=False).mean)
            for v, label in pairs]
