"""The ablation on simple objects (the figure of Padrón-Griffe et al. 2023): a sphere or a torus on the
ground under the snake scene's studio lights, in four variants --

- "diffuse": the snake's base colour alone (preset "xenopeltis-diffuse");
- "diffuse+bump": the same with the scale texture bumping the normal (no gap material);
- "thin-film+bump": the thin-film interface over the diffuse base (preset
  "xenopeltis-thin-film", a PFMC model: tabulated, or "direct"), with scales;
- "full": the full xenopeltis model (tabulated or direct), with scales and dark gaps.

Scene units are centimetres: a 10 cm sphere, a torus of radii 10 and 3.5 cm. Scales are
sized like the snake's relative to the object (about 1/18 of a circumference) and fit the
uv periods: a whole number of rows over u in [0, 1].
"""
from __future__ import annotations

from bsdflab.presets import preset
from bsdflab.render import Material, Scene, Shape
from bsdflab.scenes.material_spec import custom_bsdf
from bsdflab.scenes.snake import (
    GAP_BSDF,
    THICKNESS_JITTER,
    ground,
    ground_material,
    orbit_camera,
    sky,
    soft_box,
    tabulated,
)

VARIANTS = ("diffuse", "diffuse+bump", "thin-film+bump", "full")
OBJECTS = ("sphere", "torus")
SPHERE_RADIUS = 10.0
TORUS_RADII = (10.0, 3.5)
_SCALE_SHAPE = {"gap": 0.07, "jitter": 0.12, "dome": 0.3, "tilt_deg": 5.0,
                "thickness_jitter": THICKNESS_JITTER, "seed": 3}
# sphere: u = phi / 2 pi goes around (periodic), v = theta / pi from pole to pole (not periodic)
SPHERE_SCALES = {"scales_per_unit_u": 24.0, "scales_around": 12, **_SCALE_SHAPE, "periodic_v": False}
# torus: u around the axis, v around the tube, both periodic
TORUS_SCALES = {"scales_per_unit_u": 46.0, "scales_around": 16, **_SCALE_SHAPE, "periodic_v": True}


def _layered(name: str, material: str) -> dict:
    if material not in ("table", "direct"):
        raise ValueError(f"material must be 'table', 'direct' or a dict (a material of one's own), got {material!r}")
    model = preset(name).to_dict()
    return tabulated(model) if material == "table" else model


def ablation_material(variant: str, scales: dict, material: str | dict = "table") -> Material:
    """The object's material. ``material`` "table" or "direct" chooses how the layered
    variants' preset is evaluated; a dict (bsdflab.scenes.material_spec) replaces the
    object's BSDF in every variant, which then chooses the scales (all but "diffuse") and
    the dark gaps between them ("full")."""
    if variant not in VARIANTS:
        raise ValueError(f"unknown variant {variant!r}; known: {', '.join(VARIANTS)}")
    own = custom_bsdf(material, THICKNESS_JITTER)
    if own is None and material not in ("table", "direct"):   # refused in every variant, not only the layered
        raise ValueError(f"material must be 'table', 'direct' or a dict (a material of one's own), got {material!r}")
    if own is not None:
        if variant == "diffuse":
            return Material(own)
        return Material(own, dict(scales), dict(GAP_BSDF) if variant == "full" else None)
    if variant == "diffuse":
        return Material(preset("xenopeltis-diffuse").to_dict())
    if variant == "diffuse+bump":
        return Material(preset("xenopeltis-diffuse").to_dict(), dict(scales))
    if variant == "thin-film+bump":
        return Material(_layered("xenopeltis-thin-film", material), dict(scales))
    return Material(_layered("xenopeltis", material), dict(scales), dict(GAP_BSDF))


def object_geometry(obj: str) -> tuple[dict, dict, list[float]]:
    """(geometry spec, scale parameters, centre) of the object resting on the ground."""
    if obj == "sphere":
        centre = [0.0, SPHERE_RADIUS, 0.0]
        return ({"type": "sphere", "center": centre, "radius": SPHERE_RADIUS, "subdivisions": 192},
                SPHERE_SCALES, centre)
    if obj == "torus":
        major, minor = TORUS_RADII
        centre = [0.0, minor, 0.0]
        # minor_resolution divisible by 4: a ring of vertices lies on the ground
        return ({"type": "torus", "center": centre, "major_radius": major, "minor_radius": minor,
                 "axis": [0.0, 1.0, 0.0], "resolution": 256,
                 "minor_resolution": 96}, TORUS_SCALES, centre)
    raise ValueError(f"unknown object {obj!r}; known: {', '.join(OBJECTS)}")


def object_scene(obj: str = "sphere", variant: str = "full", width: int = 640, height: int = 360,
                 material: str | dict = "table", max_depth: int = 8) -> Scene:
    geometry, scales, centre = object_geometry(obj)
    target = [0.0, centre[1] if obj == "sphere" else 1.0, 0.0]
    distance = 62.0 if obj == "sphere" else 58.0
    shapes = (ground(), Shape(geometry, material="object", name=obj),
              soft_box([-35.0, 70.0, -30.0], target, 40.0, (14.0, 13.3, 12.4)))
    materials = {"ground": ground_material(), "object": ablation_material(variant, scales, material)}
    camera = orbit_camera(target, distance, 25.0, 30.0 if obj == "sphere" else 40.0, 40.0, width, height)
    return Scene(camera, shapes, materials, sky(), max_depth=max_depth, name=f"{obj}-{variant}")


def sphere(variant: str = "full", width: int = 640, height: int = 360, material: str | dict = "table",
           max_depth: int = 8) -> Scene:
    """A sphere on the ground in one ablation variant (diffuse, diffuse+bump, thin-film+bump, full)."""
    return object_scene("sphere", variant, width, height, material, max_depth)


def torus(variant: str = "full", width: int = 640, height: int = 360, material: str | dict = "table",
          max_depth: int = 8) -> Scene:
    """A torus on the ground in one ablation variant (diffuse, diffuse+bump, thin-film+bump, full)."""
    return object_scene("torus", variant, width, height, material, max_depth)


def ablation_row(obj: str = "sphere", width: int = 320, height: int = 240, material: str | dict = "table",
                 max_depth: int = 8) -> list[tuple[str, Scene]]:
    """The four variants of one object, as (label, scene) pairs for a contact sheet."""
    return [(variant, object_scene(obj, variant, width, height, material, max_depth)) for variant in VARIANTS]
