"""Small scenes that several test files (and the thread-count subprocesses) render."""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from bsdflab.render import Camera, Environment, Material, Scene, Shape


def light_over_plane(reflectance=0.5, emission=(2.0, 1.0, 0.5), height=1.0, half=(0.5, 1.0), size=16):
    """A diffuse floor under a downward-facing rectangle light; a very narrow camera
    looks at the floor point straight below the light's centre."""
    floor = Shape({"type": "rectangle", "center": [0, 0, 0], "normal": [0, 1, 0], "size": [20, 20]},
                  material="floor", name="floor")
    light = Shape({"type": "rectangle", "center": [0, height, 0], "normal": [0, -1, 0],
                   "size": [2 * half[0], 2 * half[1]]}, emission=emission, name="light")
    camera = Camera(origin=(0.0, 0.5, 3.0), target=(0.0, 0.0, 0.0), up=(0.0, 1.0, 0.0), fov_deg=0.05,
                    width=size, height=size)
    return Scene(camera, (floor, light), {"floor": Material({"type": "diffuse", "reflectance": reflectance})},
                 max_depth=2, name="light-over-plane")


ENV_RGB = (0.15, 0.45, 0.9)                 # a blue sky


FILM = [{"material": 1.45, "thickness_nm": 350.0}]


THETA = np.radians(50.0)                    # incidence on the plate


def film_mirror_scene(size=6):
    plate = Shape({"type": "rectangle", "center": [0, 0, 0], "normal": [0, 1, 0], "size": [50, 50]},
                  material="film", name="plate")
    camera = Camera(origin=(0.0, 3 * np.cos(THETA), 3 * np.sin(THETA)), target=(0.0, 0.0, 0.0),
                    up=(0.0, 1.0, 0.0), fov_deg=0.05, width=size, height=size)
    bsdf = {"type": "conductor", "material": "Au", "film": FILM}
    return Scene(camera, (plate,), {"film": Material(bsdf)}, Environment("constant", radiance=ENV_RGB),
                 max_depth=2, name="film-mirror")


def grey_world(size=16):
    floor = Shape({"type": "rectangle", "center": [0, 0, 0], "normal": [0, 1, 0], "size": [20, 20]},
                  material="floor", name="floor")
    ball = Shape({"type": "sphere", "center": [0, 0.6, 0], "radius": 0.5, "subdivisions": 16},
                 material="ball", name="ball")
    light = Shape({"type": "rectangle", "center": [0, 3, 0], "normal": [0, -1, 0], "size": [1, 1]},
                  emission=(4.0, 4.0, 4.0), name="light")
    camera = Camera(origin=(0.0, 1.5, 4.0), target=(0.0, 0.5, 0.0), fov_deg=40.0, width=size, height=size)
    materials = {"floor": Material({"type": "diffuse", "reflectance": 0.5}),
                 "ball": Material({"type": "roughconductor", "alpha": 0.2})}
    return Scene(camera, (floor, ball, light), materials, Environment("constant", radiance=(0.3, 0.3, 0.3)),
                 max_depth=6, rr_depth=3, name="grey-world")


FILM_TOP = {"type": "dielectric", "int_ior": 1.55, "ext_ior": 1.0,
            "film": [{"material": {"type": "constant", "n": 2.4, "k": 0.0}, "thickness_nm": 400.0}]}


# A black base under a clear slab: the layered model's scattered part is exactly zero, so its
# table is the top film's exact reflection alone and the mirror pixel has a closed form.
BLACK_LAYERED = {"type": "layered", "interfaces": [FILM_TOP], "slabs": [{"thickness_um": 1.0, "sigma_a": 0.0}],
                 "base": {"type": "diffuse", "reflectance": 0.0}, "samples": 16}


def tabulated_film_mirror_scene(size=6):
    from bsdflab.tables import TableGrid

    s = film_mirror_scene(size)
    bsdf = {"type": "tabulated", "model": BLACK_LAYERED, "grid": TableGrid(3, 4, 3).to_dict(), "rel_error": 0.5,
            "min_samples": 4, "max_samples": 8}
    return Scene(s.camera, s.shapes, {"film": Material(bsdf)}, s.environment, max_depth=2, name="table-film-mirror")


def scaled_diffuse(scene: Scene, factor: float) -> Scene:
    """``scene`` with every diffuse reflectance (constant or RGB) multiplied by ``factor``."""
    materials = {}
    for name, m in scene.materials.items():
        bsdf = dict(m.bsdf)
        if bsdf.get("type") == "diffuse":
            r = dict(bsdf["reflectance"]) if isinstance(bsdf["reflectance"], dict) else bsdf["reflectance"]
            if isinstance(r, dict) and r.get("type") == "constant":
                r["value"] = r["value"] * factor
            elif isinstance(r, dict) and r.get("type") == "rgb":
                r["rgb"] = [x * factor for x in r["rgb"]]
            elif isinstance(r, (int, float)):
                r = r * factor
            elif isinstance(r, (list, tuple)):
                r = [x * factor for x in r]
            else:
                raise ValueError(f"cannot scale reflectance {r!r}")
            bsdf["reflectance"] = r
        materials[name] = replace(m, bsdf=bsdf)
    return replace(scene, materials=materials)
