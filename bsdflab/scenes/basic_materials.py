"""Spheres in materials that Mitsuba 3 has exact counterparts for, to cross-check the
renderer: diffuse (RGB), conductor and roughconductor (constant eta/k, so the RGB render is
exact), dielectric and roughdielectric (index 1.5), GGX alpha 0.2 for the rough ones. A
rectangle area light above and, optionally, a dim constant environment."""
from __future__ import annotations

from bsdflab.render import Camera, Environment, Material, Scene, Shape

BASIC_BSDFS = {
    "diffuse": {"type": "diffuse", "reflectance": [0.7, 0.25, 0.15]},
    "conductor": {"type": "conductor", "eta": 0.2, "k": 3.0},
    "roughconductor": {"type": "roughconductor", "alpha": 0.2, "eta": 0.2, "k": 3.0},
    "dielectric": {"type": "dielectric", "int_ior": 1.5},
    "roughdielectric": {"type": "roughdielectric", "alpha": 0.2, "int_ior": 1.5},
}
SPACING = 2.4


def basic_materials(width: int = 64, height: int = 48, max_depth: int = 6, environment: bool = True,
                    subdivisions: int = 64) -> Scene:
    """Spheres of diffuse, conductor, dielectric and rough materials under an area light."""
    n = len(BASIC_BSDFS)
    shapes = [Shape({"type": "rectangle", "center": [0.0, 0.0, 0.0], "normal": [0.0, 1.0, 0.0],
                     "size": [40.0, 40.0]}, material="ground", name="ground")]
    for i, name in enumerate(BASIC_BSDFS):
        x = (i - 0.5 * (n - 1)) * SPACING
        shapes.append(Shape({"type": "sphere", "center": [x, 1.0, 0.0], "radius": 1.0,
                             "subdivisions": subdivisions}, material=name, name=name))
    shapes.append(Shape({"type": "rectangle", "center": [-2.0, 8.0, 3.0], "normal": [0.0, -1.0, 0.0],
                         "size": [4.0, 4.0]}, emission=(6.0, 6.0, 6.0), name="light"))
    materials = {"ground": Material({"type": "diffuse", "reflectance": [0.4, 0.4, 0.4]}),
                 **{name: Material(dict(bsdf)) for name, bsdf in BASIC_BSDFS.items()}}
    env = Environment(type="constant", radiance=(0.2, 0.2, 0.2)) if environment else Environment()
    camera = Camera(origin=(0.0, 4.5, 11.0), target=(0.0, 0.8, 0.0), fov_deg=60.0, width=width, height=height)
    return Scene(camera, tuple(shapes), materials, env, max_depth=max_depth, name="basic-materials")
