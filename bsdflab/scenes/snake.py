"""The sunbeam snake (*Xenopeltis unicolor*) resting on the ground, and the studio (ground,
soft box, sky) the other procedural scenes share.

Scene units are centimetres. The animal: 100 cm of body plus a 4.4 cm head, 1.8 cm
half-width mid-body (a 3.6 cm thick adult), narrowing to a 1.3 cm neck, tail tapering to a
point over its last 22 cm; three and a half bends. Scales: Xenopeltis has 15 dorsal
scale rows around mid-body plus the wide ventral plates; 18 scales around the whole
section (the texture wraps v with period 1) gives scales about 0.63 cm wide mid-body, and
1.6 rows per cm makes them about as long as wide. The head carries larger plates (fewer,
flatter scales), as real heads do.

Lighting: a 50 x 50 cm soft box above one side of the snake and a sky, so the curved body
shows the film's colours over a wide range of angles; the camera looks from a 3/4 view
above.
"""
from __future__ import annotations

import copy

import numpy as np

from bsdflab.presets import FILM_THICKNESS_NM, PRESETS, preset
from bsdflab.render import Camera, Environment, Material, Scene, Shape
from bsdflab.render.curves import SNAKE_DEFAULTS, layout_of, snake_eyes
from bsdflab.scenes.material_spec import custom_bsdf, table_grid

GROUND_RGB = [0.37, 0.35, 0.32]        # warm grey, albedo ~0.35
GAP_BSDF = {"type": "diffuse", "reflectance": [0.02, 0.018, 0.016]}
THICKNESS_JITTER = 0.15
BODY_SCALES = {"scales_per_unit_u": 1.6, "scales_around": 18, "gap": 0.07, "jitter": 0.12, "dome": 0.3,
               "tilt_deg": 5.0, "thickness_jitter": THICKNESS_JITTER, "seed": 1, "periodic_v": True}
HEAD_SCALES = {"scales_per_unit_u": 0.8, "scales_around": 8, "gap": 0.04, "jitter": 0.2, "dome": 0.15,
               "tilt_deg": 4.0, "thickness_jitter": THICKNESS_JITTER, "seed": 2, "periodic_v": True}
EYE_BSDF = {"type": "roughconductor", "alpha": 0.05, "eta": 1.5, "k": 0.0}   # black and glossy
MATERIAL_CHOICES = ("table", "direct", *PRESETS)
DIRECT_WALKS = 1


# -- the studio ---------------------------------------------------------------------------------
def ground(size: float = 800.0) -> Shape:
    return Shape({"type": "rectangle", "center": [0.0, 0.0, 0.0], "normal": [0.0, 1.0, 0.0],
                  "size": [size, size]}, material="ground", name="ground")


def ground_material() -> Material:
    return Material({"type": "diffuse", "reflectance": list(GROUND_RGB)})


def soft_box(position, target, size: float, radiance) -> Shape:
    """A square area light at ``position`` facing ``target`` (its front, emitting side)."""
    p, t = np.asarray(position, float), np.asarray(target, float)
    normal = (t - p) / np.linalg.norm(t - p)
    return Shape({"type": "rectangle", "center": p.tolist(), "normal": normal.tolist(),
                  "size": [float(size), float(size)]}, emission=tuple(float(x) for x in radiance),
                 name="soft box")


_soft_box = soft_box  # snake()'s soft_box option shadows the name there


def sky(scale: float = 0.5) -> Environment:
    return Environment(type="sky", zenith=(0.25, 0.45, 0.9), horizon=(0.9, 0.95, 1.0),
                       ground=(0.25, 0.22, 0.2), scale=scale)


def orbit_camera(target, distance: float, azimuth_deg: float, elevation_deg: float, fov_deg: float,
                 width: int, height: int) -> Camera:
    """A camera ``distance`` from ``target``; azimuth 0 looks from +Z, 90 from +X."""
    az, el = np.radians(azimuth_deg), np.radians(elevation_deg)
    offset = distance * np.array([np.sin(az) * np.cos(el), np.sin(el), np.cos(az) * np.cos(el)])
    origin = np.asarray(target, float) + offset
    return Camera(origin=tuple(origin.tolist()), target=tuple(float(x) for x in target), fov_deg=fov_deg,
                  width=width, height=height)


# -- materials ------------------------------------------------------------------------------------
def tabulated(model: dict, thickness_jitter: float = THICKNESS_JITTER, film_nm: float = FILM_THICKNESS_NM) -> dict:
    return {"type": "tabulated", "model": model, "grid": table_grid(thickness_jitter, film_nm), "rel_error": 0.02}


def snake_bsdf(material: str | dict = "table", thickness_jitter: float = THICKNESS_JITTER) -> dict:
    """The body's BSDF dict: "table" tabulates the xenopeltis preset, "direct" evaluates
    it by PFMC at every hit (slow, for validation); a preset name gives that preset,
    tabulated when it is a layered (PFMC) model; a dict is a material of one's own
    (bsdflab.scenes.material_spec)."""
    own = custom_bsdf(material, thickness_jitter)
    if own is not None:
        return own
    if material not in MATERIAL_CHOICES:
        raise ValueError(f"unknown material {material!r}; choose one of: {', '.join(MATERIAL_CHOICES)}")
    if material == "direct":
        # One PFMC walk per evaluation: still unbiased, and inside a path tracer more
        # samples per pixel beat more walks per hit.
        return preset("xenopeltis", samples=DIRECT_WALKS).to_dict()
    model = preset("xenopeltis" if material == "table" else material).to_dict()
    return tabulated(model, thickness_jitter) if model["type"] == "layered" else model


# -- the scene ----------------------------------------------------------------------------------------
def snake(width: int = 640, height: int = 360, material: str | dict = "table", scales: bool = True,
          eyes: bool = True, max_depth: int = 8, soft_box: bool = True, **shape) -> Scene:
    """The snake scene. ``shape`` overrides snake geometry parameters (SNAKE_DEFAULTS,
    e.g. ``segments=400``). ``soft_box=False`` leaves the soft box out (for lights of one's
    own, e.g. ``bsdflab render snake -o soft_box=false -o light=sun``)."""
    from bsdflab.util.args import flag

    soft_box_on = flag("soft_box", soft_box)
    spec = copy.deepcopy({**SNAKE_DEFAULTS, **shape})
    layout = layout_of(spec)
    bsdf = snake_bsdf(material)
    materials = {
        "ground": ground_material(),
        "skin": Material(bsdf, dict(BODY_SCALES), dict(GAP_BSDF)) if scales else Material(bsdf),
        "head": Material(bsdf, dict(HEAD_SCALES), dict(GAP_BSDF)) if scales else Material(bsdf),
    }
    shapes = [ground(),
              Shape({"type": "snake_body", **spec}, material="skin", name="body"),
              Shape({"type": "snake_head", **spec}, material="head", name="head")]
    if eyes:
        materials["eye"] = Material(dict(EYE_BSDF))
        shapes += [Shape({"type": "sphere", "center": c, "radius": r, "subdivisions": 24}, material="eye",
                         name=f"eye {i}") for i, (c, r) in enumerate(snake_eyes(layout))]
    centre = np.append(layout.xz_dense.mean(axis=0), 0.0)[[0, 2, 1]] + [0.0, 2.0, 0.0]
    if soft_box_on:
        shapes.append(_soft_box(centre + [-45.0, 85.0, -40.0], centre, 50.0, (14.0, 13.3, 12.4)))
    camera = orbit_camera(centre, 100.0, 25.0, 36.0, 42.0, width, height)
    return Scene(camera, tuple(shapes), materials, sky(), max_depth=max_depth, name="snake")
