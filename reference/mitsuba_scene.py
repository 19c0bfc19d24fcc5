"""A bsdflab ``Scene`` as a Mitsuba 3 scene dict, for image-level cross-checks.

    scene_dict = to_mitsuba_scene(scene)      # then mi.load_dict(scene_dict)

What goes over, and how it matches our renderer (bsdflab/render/build.py):
  * shapes: the very triangles, vertex normals and uvs our renderer gets from
    ``bsdflab.render.geometry.build_mesh``, as ``mi.Mesh`` objects filled in memory (float32
    like ours). Without vertex normals both codes shade with the face normal (Mitsuba
    computes no normals for a mesh built this way). A shape without a material is black:
    Mitsuba's default BSDF (grey diffuse) is replaced by a zero-albedo diffuse.
  * emission: an ``area`` emitter with the RGB radiance; it emits on the side the shading
    normal points to, as ours does.
  * materials: ``to_mitsuba`` (mitsuba_bsdf.py) for models with a Mitsuba counterpart; table
    BSDFs ("table" files and "tabulated" requests, resolved through our renderer's cache)
    through the ``bsdflab_table`` plugin (table_plugin.py); materials with scales raise
    ValueError (Mitsuba has no scale texture). ``bsdflab_fallback=True`` also sends models
    without a counterpart (layered, thin films, named metals in RGB) through the plugin --
    then the image checks light transport only.
  * environment: "constant" -> ``constant``; "sky" / "envmap" -> ``envmap`` from the very
    lat-long image our renderer uses (bsdflab/render/environment.py), times ``scale``.
    The two codes place rows differently, see ``mitsuba_latlong``. A sun light's sky goes
    over the same way (RGB only).
  * lights: ``point``, ``spot`` (same cutoff, beam width and linear falloff), ``directional``
    with the same parameters; a sun as its directional light (its spectrum in spectral
    mode). Soft suns (an angular diameter) have no counterpart and are refused.
  * camera: ``perspective`` from ``look_at`` with the horizontal fov; box-filtered
    ``hdrfilm``; ``path`` integrator with max_depth / rr_depth; ``independent`` sampler.
  * ``spectral=True`` (for a Mitsuba spectral variant; our ``render(spectral=True)``):
    emission, constant environments and BSDF parameters as the explicit 81-bin spectra our
    renderer uses (mitsuba_spectral.py, with the conventions and what cannot go over).
"""
from __future__ import annotations

import math
from typing import Any

import numpy as np

from bsdflab.reference.mitsuba_bsdf import to_mitsuba
from bsdflab.reference.mitsuba_env import mitsuba
from bsdflab.reference.mitsuba_spectral import emission as spectral_emission
from bsdflab.reference.mitsuba_spectral import environment as spectral_environment
from bsdflab.reference.mitsuba_spectral import step_spectrum_dict, to_mitsuba_spectral
from bsdflab.render.lights import Light, colour_of
from bsdflab.render.scene import Material, Scene, Shape
from bsdflab.render.sky import sky_image, sky_sun, sun_irradiance, sun_spectrum

# Mitsuba's perspective camera clips at near_clip (ours does not clip): a small fraction of
# the camera's distance to its target keeps the clip far below any scene feature.
NEAR_CLIP_FRACTION = 1e-4
FAR_CLIP_FRACTION = 1e5
BLACK = {"type": "diffuse", "reflectance": 0.0}


def to_mitsuba_scene(scene: Scene, spp: int = 16, base_dir: str | None = None,
                     bsdflab_fallback: bool = False, cache_dir=None, spectral: bool = False) -> dict[str, Any]:
    """The ``mi.load_dict`` dict of ``scene`` (Mitsuba's reference variant must stay active
    while it is loaded: shapes are already Mitsuba objects).

    spp: the sampler's default sample count (``mi.render(..., spp=)`` overrides it).
    base_dir: where relative mesh and map paths are resolved, as for our renderer.
    bsdflab_fallback: render BSDFs without a Mitsuba counterpart with bsdflab's own code
    through the plugin instead of raising ValueError (RGB only).
    spectral: the scene of our spectral mode, for a Mitsuba spectral variant (active).
    """
    if not isinstance(scene, Scene):
        raise ValueError(f"scene must be a bsdflab.render.Scene, got {type(scene).__name__}")
    mi = mitsuba() if not spectral else _spectral_mitsuba()
    if spectral and bsdflab_fallback:
        raise ValueError("bsdflab_fallback is RGB only: the bsdflab plugin answers in RGB, a spectral "
                         "Mitsuba path needs the answer at its own wavelengths")
    material = _spectral_material if spectral else _material
    bsdfs = {name: material(name, m, bsdflab_fallback, cache_dir) for name, m in scene.materials.items()}
    out: dict[str, Any] = {"type": "scene", "sensor": _sensor(mi, scene, spp),
                           "integrator": path_integrator(scene)}
    for i, shape in enumerate(scene.shapes):
        bsdf = bsdfs[shape.material] if shape.material is not None else BLACK
        out[f"shape_{i}"] = _mesh(mi, shape, i, bsdf, base_dir, spectral)
    env = spectral_environment(scene.environment) if spectral else _environment(mi, scene, base_dir)
    if sky_sun(scene.lights) is not None:  # the sun preset's sky replaces the environment, as ours
        env = _sun_sky(mi, sky_sun(scene.lights), spectral)
    if env is not None:
        out["environment"] = env
    for i, light in enumerate(scene.lights):
        out[f"light_{i}"] = _light(mi, light, spectral)
    return out


def path_integrator(scene: Scene) -> dict[str, Any]:
    return {"type": "path", "max_depth": scene.max_depth, "rr_depth": scene.rr_depth}


# -- pieces -----------------------------------------------------------------------------------
def _material(name: str, material: Material, fallback: bool, cache_dir) -> dict[str, Any]:
    from bsdflab.reference.table_plugin import plugin_dict

    if material.scales is not None:
        raise ValueError(f"material {name!r} has scales: Mitsuba has no scale texture (bump and "
                         "film-thickness variation), so it cannot reproduce it")
    kind = material.bsdf.get("type")
    if kind == "tabulated":
        from bsdflab.render.build import resolve_bsdf  # our renderer's own table resolution

        return plugin_dict(resolve_bsdf(material.bsdf, cache_dir=cache_dir))
    if kind == "table":
        from bsdflab.tables import TableBSDF

        return plugin_dict(TableBSDF(**{k: v for k, v in material.bsdf.items() if k != "type"}))
    try:
        return to_mitsuba(material.bsdf)
    except ValueError as e:
        if not fallback:
            raise ValueError(f"material {name!r}: {e}") from None
    from bsdflab.bsdfs import from_dict

    return plugin_dict(from_dict(material.bsdf))


def _spectral_mitsuba():
    import mitsuba as mi

    if not mi.variant() or "spectral" not in mi.variant():
        raise ValueError(f"spectral=True needs a Mitsuba spectral variant active, not {mi.variant()!r}")
    return mi


def _spectral_material(name: str, material: Material, fallback: bool, cache_dir) -> dict[str, Any]:
    if material.scales is not None:
        raise ValueError(f"material {name!r} has scales: Mitsuba has no scale texture")
    if material.bsdf.get("type") in ("tabulated", "table"):
        raise ValueError(f"material {name!r}: a table answers in RGB (our spectral mode lifts its answer); "
                         "Mitsuba's spectral variants would need the answer at each path's wavelengths")
    try:
        return to_mitsuba_spectral(material.bsdf)
    except ValueError as e:
        raise ValueError(f"material {name!r}: {e}") from None


def _mesh(mi, shape: Shape, index: int, bsdf: dict[str, Any], base_dir, spectral: bool = False):
    from bsdflab.render.geometry import build_mesh

    try:
        mesh = build_mesh(shape.geometry, base_dir)
    except ValueError as e:
        raise ValueError(f"shape {shape.name!r}: {e}") from None
    positions = np.asarray(mesh.positions, dtype=np.float32)
    faces = np.asarray(mesh.indices, dtype=np.uint32)
    normals = None if mesh.normals is None else np.asarray(mesh.normals, dtype=np.float32)
    uvs = None if mesh.uvs is None else np.asarray(mesh.uvs, dtype=np.float32)

    props = mi.Properties()
    props["bsdf"] = mi.load_dict(bsdf)
    if shape.emission is not None:
        radiance = spectral_emission(shape.emission) if spectral else _rgb(shape.emission)
        props["emitter"] = mi.load_dict({"type": "area", "radiance": radiance})
    m = mi.Mesh(shape.name or f"shape_{index}", len(positions), len(faces), props=props,
                has_vertex_normals=normals is not None, has_vertex_texcoords=uvs is not None)
    params = mi.traverse(m)
    params["vertex_positions"] = np.ascontiguousarray(positions.ravel())
    params["faces"] = np.ascontiguousarray(faces.ravel())
    if normals is not None:
        params["vertex_normals"] = np.ascontiguousarray(normals.ravel())
    if uvs is not None:
        params["vertex_texcoords"] = np.ascontiguousarray(uvs.ravel())
    params.update()
    return m


def _rgb(value) -> dict[str, Any]:
    return {"type": "rgb", "value": [float(x) for x in value]}


def _environment(mi, scene: Scene, base_dir) -> dict[str, Any] | None:
    env = scene.environment
    if env.type == "none":
        return None
    if env.type == "constant":
        return {"type": "constant", "radiance": _rgb(env.radiance)}
    from bsdflab.render.environment import environment_image

    image = environment_image(env, base_dir)
    return {"type": "envmap", "bitmap": mi.Bitmap(mitsuba_latlong(image)), "scale": float(env.scale)}


def _light(mi, light: Light, spectral: bool) -> dict[str, Any]:
    """Mitsuba's ``point``, ``spot`` or ``directional`` emitter for one of our lights (same
    parameters and units); a sun is its directional light. A soft directional light (an
    angular diameter > 0, every sun) has no Mitsuba counterpart: ValueError."""
    def colour(value):  # our renderer's colour of the light, as a Mitsuba spectrum
        rgb, bins = colour_of(value)
        if not spectral:
            return _rgb(rgb)
        return step_spectrum_dict(bins, "zero") if bins else spectral_emission(rgb)

    if light.type == "point":
        return {"type": "point", "position": list(light.position), "intensity": colour(light.intensity)}
    if light.type == "spot":
        p, d = np.asarray(light.position), np.asarray(light.direction, dtype=float)
        helper = [1.0, 0.0, 0.0] if abs(d[0]) < 0.9 * np.linalg.norm(d) else [0.0, 1.0, 0.0]
        return {"type": "spot", "intensity": colour(light.intensity), "cutoff_angle": light.cutoff_angle_deg,
                "beam_width": light.beam_width_deg,
                "to_world": mi.ScalarTransform4f().look_at(origin=p.tolist(), target=(p + d).tolist(), up=helper)}
    if light.angular_diameter_deg > 0:
        raise ValueError(f"{light.type} light {light.name!r}: an angular diameter > 0 (a soft sun) has no Mitsuba "
                         "counterpart (its directional emitter is a delta light); set angular_diameter_deg to 0")
    if light.type == "directional":
        return {"type": "directional", "direction": list(light.direction), "irradiance": colour(light.irradiance)}
    irradiance = step_spectrum_dict(sun_spectrum(light).tolist(), "zero") if spectral else colour(sun_irradiance(light))
    return {"type": "directional", "direction": (-light.sun_direction()).tolist(), "irradiance": irradiance}


def _sun_sky(mi, sun: Light, spectral: bool) -> dict[str, Any]:
    if spectral:
        raise ValueError("the sun's sky is a lat-long environment: it has no spectral Mitsuba counterpart "
                         "(see mitsuba_spectral.environment); set \"sky\": false")
    image = sky_image(sun.sun_direction(), sun.turbidity)
    return {"type": "envmap", "bitmap": mi.Bitmap(mitsuba_latlong(image)), "scale": float(sun.scale)}


def mitsuba_latlong(image: np.ndarray) -> np.ndarray:
    """The image Mitsuba's ``envmap`` must get to show what our renderer shows for ``image``.

    Both codes interpolate bilinearly with texel-centred columns (u = (i + 1/2) / W). Rows
    differ: ours are texel-centred too (v_j = (j + 1/2) / H, constant beyond the first and
    last centre), while Mitsuba 3.9 puts row j at v = j / (H - 1) (first row at the +Y
    pole, last at -Y). Both are piecewise linear in v, so a 2H + 1 row image whose odd rows
    are ours, whose inner even rows are the averages of their neighbours and whose first /
    last rows repeat ours reproduces our radiance exactly in every direction.
    """
    a = np.asarray(image, dtype=np.float64)
    if a.ndim != 3 or a.shape[2] != 3:
        raise ValueError(f"expected an (H, W, 3) lat-long image, got shape {a.shape}")
    h = a.shape[0]
    out = np.empty((2 * h + 1,) + a.shape[1:])
    out[1::2] = a
    out[2:-1:2] = 0.5 * (a[:-1] + a[1:])
    out[0], out[-1] = a[0], a[-1]
    return out.astype(np.float32)


def _sensor(mi, scene: Scene, spp: int) -> dict[str, Any]:
    c = scene.camera
    distance = math.dist(c.origin, c.target)
    return {
        "type": "perspective",
        "to_world": mi.ScalarTransform4f().look_at(origin=list(c.origin), target=list(c.target),
                                                   up=list(c.up)),
        "fov": float(c.fov_deg),
        "fov_axis": "x",
        "near_clip": NEAR_CLIP_FRACTION * distance,
        "far_clip": FAR_CLIP_FRACTION * distance,
        "film": {"type": "hdrfilm", "width": c.width, "height": c.height,
                 "rfilter": {"type": "box"}, "pixel_format": "rgb", "component_format": "float32"},
        "sampler": {"type": "independent", "sample_count": int(spp)},
    }
