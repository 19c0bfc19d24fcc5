"""What a scene is: plain, validated, JSON-round-trippable descriptions.

World conventions (the same as Mitsuba 3, so scenes convert one-to-one): +Y is up; the
ground is the plane y = 0; lengths are in scene units (the snake scene uses centimetres);
colours and radiances are linear sRGB (D65). A scene names its geometry by *spec dicts*
(``{"type": "sphere", ...}``, built into triangle meshes by ``bsdflab.render.geometry``),
its materials by bsdflab BSDF dicts, and its lights as emissive shapes, an environment and
lights without geometry (point, spot, directional, sun: ``bsdflab.render.lights``).

Nothing here computes light transport: ``bsdflab.render.render`` turns a ``Scene`` into the
C++ renderer's input.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, fields, replace
from typing import Any

import numpy as np

from bsdflab.render.lights import Light, lights_of
from bsdflab.util import limits
from bsdflab.util.args import brief, integer, nesting

ENVIRONMENT_TYPES = ("none", "constant", "sky", "envmap")
MAX_RESOLUTION = 16384
MAX_PIXELS = limits.DEFAULTS["BSDFLAB_MAX_PIXELS"]  # the default; BSDFLAB_MAX_PIXELS overrides


def _vec3(name: str, value: Any, nonnegative: bool = False) -> tuple[float, float, float]:
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(f"{name} must be 3 finite numbers, got {brief(value)}") from None
    if a.ndim == 0:
        a = np.full(3, float(a))
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be 3 finite numbers, got {brief(value)}")
    if nonnegative and np.any(a < 0):
        raise ValueError(f"{name} must be >= 0, got {brief(value)}")
    return (float(a[0]), float(a[1]), float(a[2]))


def _positive(name: str, value: Any, hi: float = math.inf) -> float:
    if isinstance(value, (str, bytes, bool)):
        raise ValueError(f"{name} must be a number, got {brief(value)}")
    try:
        v = float(value)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(f"{name} must be a finite number, got {brief(value)}") from None
    if not (0 < v < hi) or not math.isfinite(v):
        raise ValueError(f"{name} must be in (0, {hi}), got {brief(value)}")
    return v


@dataclass(frozen=True)
class Camera:
    """A pinhole camera looking from ``origin`` at ``target``.

    ``fov_deg`` is the horizontal field of view (Mitsuba's ``fov_axis="x"``). Image x grows
    to the right (cross(view direction, up)), image y downwards; pixel (0, 0) is top left.
    """

    origin: tuple[float, float, float] = (0.0, 1.0, 5.0)
    target: tuple[float, float, float] = (0.0, 1.0, 0.0)
    up: tuple[float, float, float] = (0.0, 1.0, 0.0)
    fov_deg: float = 40.0
    width: int = 320
    height: int = 240

    def __post_init__(self):
        for name in ("origin", "target", "up"):
            object.__setattr__(self, name, _vec3(f"camera {name}", getattr(self, name)))
        object.__setattr__(self, "fov_deg", _positive("camera fov_deg", self.fov_deg, 179.0))
        object.__setattr__(self, "width", integer("width", self.width, 1, MAX_RESOLUTION))
        object.__setattr__(self, "height", integer("height", self.height, 1, MAX_RESOLUTION))
        limits.check_count("width x height", self.width * self.height, "BSDFLAB_MAX_PIXELS")
        if max(abs(x) for x in (*self.origin, *self.target)) > 1e15:
            raise ValueError("camera origin and target must be within 1e15 of the world origin")
        d = np.subtract(self.target, self.origin)
        if np.linalg.norm(d) < 1e-9 * max(1.0, np.abs(self.origin).max()):
            raise ValueError("camera origin and target must differ")
        if np.linalg.norm(np.cross(d, self.up)) <= 1e-9 * np.linalg.norm(d) * np.linalg.norm(self.up):
            raise ValueError("camera up must not be parallel to the view direction")


@dataclass(frozen=True)
class Shape:
    """A surface: a geometry spec, the material on it and, for an area light, its emission.

    geometry : dict
        ``{"type": ..., parameters}``; the types and their parameters are documented in
        ``bsdflab.render.geometry`` (sphere, torus, rectangle, snake_body, snake_head, mesh).
    material : str or None
        Key into ``Scene.materials``; None makes a black surface (a pure emitter).
    emission : 3 numbers or None
        Radiance (linear sRGB) leaving the front side -- the side its normals point to.
    """

    geometry: dict
    material: str | None = None
    emission: tuple[float, float, float] | None = None
    name: str = ""

    def __post_init__(self):
        if not isinstance(self.geometry, dict) or not isinstance(self.geometry.get("type"), str):
            raise ValueError(f"shape {self.name!r}: geometry must be a dict with a string 'type'")
        if self.emission is not None:
            e = _vec3(f"shape {self.name!r} emission", self.emission, True)
            if max(e) > 1e12:
                raise ValueError(f"shape {self.name!r} emission must be <= 1e12, got {e}")
            object.__setattr__(self, "emission", e)
        if self.material is None and self.emission is None:
            raise ValueError(f"shape {self.name!r} has neither a material nor an emission")


@dataclass(frozen=True)
class Material:
    """A BSDF on a surface, optionally with procedural hexagonal scales.

    bsdf : dict
        A bsdflab BSDF dict (``bsdflab.bsdfs.from_dict``), or a table request
        ``{"type": "tabulated", "model": <BSDF dict>, "grid": <TableGrid dict>,
        "rel_error": 0.02}`` that the renderer resolves through the table cache (tabulating
        on first use).
    scales : dict or None
        Parameters of ``bsdflab.render.textures.ScaleTexture`` (driven by the surface's
        (u, v)): per-scale normal dome/tilt (bump mapping) and film-thickness variation.
    gap_bsdf : dict or None
        BSDF in the gaps between scales (dark skin); None keeps ``bsdf`` there.
    """

    bsdf: dict
    scales: dict | None = None
    gap_bsdf: dict | None = None

    def __post_init__(self):
        if not isinstance(self.bsdf, dict) or "type" not in self.bsdf:
            raise ValueError("material bsdf must be a BSDF dict with a 'type' key")
        if self.gap_bsdf is not None and (not isinstance(self.gap_bsdf, dict) or "type" not in self.gap_bsdf):
            raise ValueError("material gap_bsdf must be a BSDF dict with a 'type' key")
        if self.gap_bsdf is not None and self.scales is None:
            raise ValueError("material gap_bsdf needs scales")
        if self.scales is not None and not isinstance(self.scales, dict):
            raise ValueError("material scales must be a dict of ScaleTexture parameters")


@dataclass(frozen=True)
class Environment:
    """Light from infinitely far away.

    type "none": black; "constant": ``radiance`` from every direction; "sky": a gradient
    from ``horizon`` to ``zenith`` above the horizon and ``ground`` below; "envmap": a
    lat-long EXR at ``path`` (Mitsuba's mapping: u = atan2(x, -z) / 2pi, v = acos(y) / pi),
    times ``scale``. Sky and envmap are importance-sampled by their luminance.
    """

    type: str = "none"
    radiance: tuple[float, float, float] = (1.0, 1.0, 1.0)
    zenith: tuple[float, float, float] = (0.25, 0.45, 0.9)
    horizon: tuple[float, float, float] = (0.9, 0.95, 1.0)
    ground: tuple[float, float, float] = (0.25, 0.22, 0.2)
    path: str | None = None
    scale: float = 1.0

    def __post_init__(self):
        if self.type not in ENVIRONMENT_TYPES:
            raise ValueError(f"unknown environment type {self.type!r}; known: {', '.join(ENVIRONMENT_TYPES)}")
        for name in ("radiance", "zenith", "horizon", "ground"):
            object.__setattr__(self, name, _vec3(f"environment {name}", getattr(self, name), True))
        object.__setattr__(self, "scale", _positive("environment scale", self.scale, 1e12))
        if self.path is not None and not isinstance(self.path, str):
            raise ValueError(f"environment path must be a string, got {type(self.path).__name__}")
        if self.type == "envmap" and not self.path:
            raise ValueError("an envmap environment needs a path")


@dataclass(frozen=True)
class Scene:
    """Everything a render needs apart from the sample count.

    ``max_depth`` follows Mitsuba: the longest path in vertices counted from the camera,
    1 = emitters seen directly, 2 = direct lighting, ...; ``rr_depth`` is the depth from
    which Russian roulette may end paths.
    """

    camera: Camera
    shapes: tuple[Shape, ...]
    materials: dict[str, Material] = field(default_factory=dict)
    environment: Environment = field(default_factory=Environment)
    max_depth: int = 8
    rr_depth: int = 5
    name: str = "scene"
    lights: tuple[Light, ...] = ()

    def __post_init__(self):
        object.__setattr__(self, "shapes", tuple(self.shapes))
        object.__setattr__(self, "lights", lights_of(self.lights))
        if not self.shapes:
            raise ValueError("a scene needs at least one shape")
        for s in self.shapes:
            if s.material is not None and s.material not in self.materials:
                raise ValueError(f"shape {s.name!r} uses unknown material {s.material!r}; "
                                 f"materials: {', '.join(sorted(self.materials)) or '(none)'}")
        object.__setattr__(self, "max_depth", integer("max_depth", self.max_depth, 1, 1024))
        object.__setattr__(self, "rr_depth", integer("rr_depth", self.rr_depth, 1, 1024))
        if (self.environment.type == "none" and not self.lights
                and not any(s.emission and max(s.emission) > 0 for s in self.shapes)):
            raise ValueError("the scene has no light: add an emissive shape, an environment or a light")

    def with_resolution(self, width: int, height: int) -> Scene:
        return replace(self, camera=replace(self.camera, width=width, height=height))

    # -- dict form (scene files, the HTTP API) -----------------------------------------
    def to_dict(self) -> dict[str, Any]:
        lights = {"lights": [light.to_dict() for light in self.lights]} if self.lights else {}
        return {
            "name": self.name,
            "camera": _plain(self.camera),
            "shapes": [_plain(s) for s in self.shapes],
            "materials": {k: _plain(m) for k, m in self.materials.items()},
            "environment": _plain(self.environment),
            "max_depth": self.max_depth,
            "rr_depth": self.rr_depth,
            **lights,  # only when there are any: older scene dicts (and their hashes) stay as they were
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> Scene:
        if not isinstance(d, dict):
            raise ValueError("a scene must be a dict")
        nesting("the scene", d)
        unknown = set(d) - {"name", "camera", "shapes", "materials", "environment", "max_depth", "rr_depth",
                            "lights"}
        if unknown:
            raise ValueError(f"unknown scene keys: {', '.join(sorted(unknown))}")
        try:
            return cls(
                camera=_build(Camera, d.get("camera", {})),
                shapes=tuple(_build(Shape, s) for s in d.get("shapes", ())),
                materials={str(k): _build(Material, m) for k, m in dict(d.get("materials", {})).items()},
                environment=_build(Environment, d.get("environment", {})),
                max_depth=d.get("max_depth", 8),
                rr_depth=d.get("rr_depth", 5),
                name=str(d.get("name", "scene")),
                lights=lights_of(d.get("lights", ())),
            )
        except (TypeError, KeyError, OverflowError, AttributeError) as e:
            raise ValueError(f"bad scene: {e}") from None


def _plain(obj) -> dict[str, Any]:
    out = {}
    for f in fields(obj):
        v = getattr(obj, f.name)
        out[f.name] = list(v) if isinstance(v, tuple) else v
    return out


def _build(cls, d):
    if not isinstance(d, dict):
        raise ValueError(f"{cls.__name__.lower()} must be a dict, got {type(d).__name__}")
    names = {f.name for f in fields(cls)}
    unknown = set(d) - names
    if unknown:
        raise ValueError(f"unknown {cls.__name__.lower()} keys: {', '.join(sorted(unknown))}; "
                         f"known: {', '.join(sorted(names))}")
    return cls(**d)
