"""Turn a ``Scene`` into the C++ renderer's ``RenderScene``, resolving everything that can
fail (unknown materials, unreadable meshes or maps, tables) before any rendering starts."""
from __future__ import annotations

import json
import logging
from typing import Any

import numpy as np

from bsdflab import _core
from bsdflab.bsdfs.base import BSDF, from_dict
from bsdflab.render.environment import environment_image
from bsdflab.render.geometry import build_mesh
from bsdflab.render.lights import add_to_core
from bsdflab.render.scene import Material, Scene
from bsdflab.render.sky import sky_image, sky_sun
from bsdflab.render.textures import ScaleTexture
from bsdflab.spectra import DEFAULT_WAVELENGTHS, rgb_to_spectrum, srgb_weights
from bsdflab.tables.cache import get
from bsdflab.tables.request import TABULATED, TableRequest
from bsdflab.tables.table_bsdf import TableBSDF, default_film_thickness
from bsdflab.util import limits

log = logging.getLogger(__name__)


def resolve_bsdf(d: dict[str, Any], progress: bool = False, cache_dir=None, spectral: bool = False) -> BSDF:
    """A BSDF from its dict; ``{"type": "tabulated", "model": ..., ...}`` (a table request,
    bsdflab.tables.request: ``grid``, ``rel_error``, ``method`` (default "auto":
    adding-doubling wherever it covers the model), PFMC's ``min_samples``, ``max_samples``,
    ``seed``, the solver's ``nodes``, ``orders``) gives the table of ``model`` from the
    cache, tabulating it first when it is not there.

    ``spectral``: for a spectral render, a table of a spectral model stores the 81 bins of
    the default grid (its own cache entry), so iridescent spectra multiply bin by bin along
    a path; an RGB render keeps the RGB table (3 channels: 27x less work per lookup)."""
    if d.get("type") != TABULATED:
        return from_dict(d)
    request = table_request(d, spectral)
    table, path, hit = get(request, cache=cache_dir, progress=progress)
    accuracy = table.accuracy()
    if not accuracy["target_met"]:
        log.warning("table %s: %s", path, accuracy["advice"])
    log.info("table %s %s by %s (%s)", path, "reused from the cache" if hit else "tabulated", request.method,
             request.method_note)
    return TableBSDF(table, path=None if path is None else str(path))  # the file: what Dask ships


def table_request(d: dict[str, Any], spectral: bool = False) -> TableRequest:
    """The table request of a ``{"type": "tabulated", ...}`` material in a render that is
    ``spectral`` or not (see ``resolve_bsdf``)."""
    if "wavelengths" in d:
        raise ValueError("a tabulated BSDF's channels follow the render (RGB or spectral): drop 'wavelengths'")
    model = from_dict(d["model"]) if isinstance(d.get("model"), dict) else None
    wavelengths = DEFAULT_WAVELENGTHS if spectral and model is not None and not _spectrally_flat(model) else None
    return TableRequest.from_dict(d, wavelengths=wavelengths)


def _spectrally_flat(model: BSDF) -> bool:
    """A model whose renderer core is one channel (no wavelength dependence): a spectral
    table of it would store 81 equal channels."""
    core, _ = model.render_core()
    return core.channels == 1


def film_thickness(bsdf: BSDF) -> float:
    """The film thickness (nm) a scale texture modulates, or -1 without a film."""
    if isinstance(bsdf, TableBSDF):
        return bsdf.film_thickness_nm
    return default_film_thickness(bsdf.to_dict())


def _projection(P) -> list[float]:
    return [] if P is None else np.asarray(P, dtype=float).ravel().tolist()


def spectral_lift(core, P, bsdf: BSDF | None = None) -> list[float]:
    """The (81 x C) lift of a render core's channels to the spectral bins of the default grid
    ([] when its channels are those bins): the model's own (``BSDF.render_lift``, e.g.
    Diffuse's reflectance spectrum, tabulated ones included); else RGB cores (P None)
    through Mallett & Yuksel's linear basis -- for RGB tables an approximation (the table
    was integrated to RGB) --, one-channel (spectrally flat) cores by broadcasting."""
    n = len(DEFAULT_WAVELENGTHS)
    own = bsdf.render_lift() if bsdf is not None else None
    if own is not None:
        own = np.asarray(own, dtype=float)
        if own.shape != (n, core.channels):
            raise ValueError(f"render_lift must be ({n}, {core.channels}), got {own.shape}")
        return own.ravel().tolist()
    if P is None:
        return rgb_to_spectrum(np.eye(3), DEFAULT_WAVELENGTHS).T.ravel().tolist()
    if core.channels == n:
        return []
    if core.channels == 1:
        return [1.0] * n
    raise ValueError(f"a render core with {core.channels} channels has no spectral form")


def _resolver(progress: bool, cache_dir, spectral: bool = False):
    """resolve_bsdf memoised by the BSDF dict for one scene build: materials that share a
    BSDF (the snake's body and head) share its core object and its precomputation."""
    memo: dict[str, BSDF] = {}

    def resolve(d: dict[str, Any]) -> BSDF:
        key = json.dumps(d, sort_keys=True, default=repr)
        if key not in memo:
            memo[key] = resolve_bsdf(d, progress, cache_dir, spectral)
        return memo[key]

    return resolve


def _add_material(core_scene, material: Material, resolve) -> int:
    surface = resolve(material.bsdf)
    core, P = surface.render_core()
    gap_core, gap_P, gap_U = None, None, []
    if material.gap_bsdf is not None:
        gap = resolve(material.gap_bsdf)
        gap_core, gap_P = gap.render_core()
        gap_U = spectral_lift(gap_core, gap_P, gap)
    scales = ScaleTexture.from_dict(material.scales).to_core() if material.scales is not None else None
    return core_scene.add_material(core, _projection(P), gap_core, _projection(gap_P), scales,
                                   film_thickness(surface), spectral_lift(core, P, surface), gap_U)


def build_render_scene(scene: Scene, base_dir: str | None = None, progress: bool = False, cache_dir=None,
                       spectral: bool = False):
    """The committed ``_core.RenderScene`` for ``scene``; relative mesh and map paths are
    resolved against ``base_dir``. ``spectral``: built for a spectral render (tables of
    spectral models store the spectral bins, see ``resolve_bsdf``)."""
    c = scene.camera  # the image buffers come after the meshes: count them in from the start
    limits.check_bytes(f"a {c.width} x {c.height} render", limits.render_bytes(c.width, c.height))
    core_scene = _core.RenderScene()
    material_ids = {}
    triangles = 0
    resolve = _resolver(progress, cache_dir, spectral)
    for name, material in scene.materials.items():
        try:
            material_ids[name] = _add_material(core_scene, material, resolve)
        except ValueError as e:
            raise ValueError(f"material {name!r}: {e}") from None
    for shape in scene.shapes:
        try:
            mesh = build_mesh(shape.geometry, base_dir)
        except ValueError as e:
            raise ValueError(f"shape {shape.name!r}: {e}") from None
        triangles += len(mesh.indices)  # the scene's meshes stay in the core for the render
        limits.check_count("the scene's triangles", triangles, "BSDFLAB_MAX_TRIANGLES")
        limits.check_bytes(f"the scene's meshes ({triangles} triangles) and a {c.width} x {c.height} render",
                           limits.SCENE_BYTES_PER_TRIANGLE * triangles + limits.render_bytes(c.width, c.height))
        core_scene.add_mesh(np.asarray(mesh.positions, dtype=np.float32),
                            np.asarray(mesh.indices, dtype=np.uint32),
                            None if mesh.normals is None else np.asarray(mesh.normals, dtype=np.float32),
                            None if mesh.uvs is None else np.asarray(mesh.uvs, dtype=np.float32),
                            material_ids.get(shape.material, -1),
                            list(shape.emission or (0.0, 0.0, 0.0)))
    wl = DEFAULT_WAVELENGTHS
    core_scene.set_spectral(rgb_to_spectrum(np.eye(3), wl).T.ravel().tolist(), srgb_weights(wl).ravel().tolist())
    c = scene.camera
    core_scene.set_camera(list(c.origin), list(c.target), list(c.up), c.fov_deg, c.width, c.height)
    env = scene.environment
    sun = sky_sun(scene.lights)
    if sun is not None:  # the sun preset's sky replaces the scene's environment
        core_scene.set_environment_map(sky_image(sun.sun_direction(), sun.turbidity), sun.scale)
    elif env.type == "constant":
        core_scene.set_environment_constant(list(env.radiance))
    else:
        image = environment_image(env, base_dir)
        if image is not None:
            core_scene.set_environment_map(image, env.scale)
    for i, light in enumerate(scene.lights):
        try:
            add_to_core(core_scene, light)
        except ValueError as e:
            raise ValueError(f"light {i}: {e}") from None
    core_scene.commit()
    return core_scene
