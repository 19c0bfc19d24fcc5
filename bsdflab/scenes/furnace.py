"""The white furnace: a diffuse sphere of reflectance 1 inside a constant environment of
radiance 1 and nothing else. Every path ends in the environment with weight 1 (a convex
Lambertian reflector of albedo 1 loses and absorbs nothing), so every pixel's expected
value is exactly 1 once ``max_depth`` allows the few bounces a convex object needs."""
from __future__ import annotations

from bsdflab.render import Camera, Environment, Material, Scene, Shape


def furnace(width: int = 64, height: int = 48, reflectance: float = 1.0, max_depth: int = 64,
            subdivisions: int = 64) -> Scene:
    """A white diffuse sphere in a uniform unit environment: renders to 1 everywhere."""
    sphere = Shape({"type": "sphere", "center": [0.0, 0.0, 0.0], "radius": 1.0, "subdivisions": subdivisions},
                   material="white", name="sphere")
    materials = {"white": Material({"type": "diffuse", "reflectance": float(reflectance)})}
    camera = Camera(origin=(0.0, 0.0, 4.0), target=(0.0, 0.0, 0.0), fov_deg=45.0, width=width, height=height)
    return Scene(camera, (sphere,), materials, Environment(type="constant", radiance=(1.0, 1.0, 1.0)),
                 max_depth=max_depth, rr_depth=max_depth, name="furnace")
