"""Image-level cross-checks of our path tracer against Mitsuba 3 (``path`` integrator).

Each check renders the same scene in both codes and runs ``image_z_test`` at
ALPHA = 1e-3: a correct pair of renderers fails one check in a thousand (Sidak over all
pixel-channels; the seeds are fixed, so outcomes are repeatable). SPP is chosen so pixel
means are close to Gaussian and a few-percent bias in any region is far beyond the noise.
On failure, a figure (both images and the z map) is written to BSDFLAB_TEST_FIGURES
(default: pytest's tmp folder) and named in the message.

Not checked against Mitsuba: the sphere's "diffuse+bump" variant. Mitsuba has no
counterpart of our scale texture (bump and film-thickness variation), so
``to_mitsuba_scene`` refuses it (tested below) rather than render something else.
"""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from bsdflab.render import Camera, Environment, Material, Scene, Shape, render
from bsdflab.testing import image_z_test
from bsdflab.validation.checks.renderer import sphere_on_floor
from support.render_scenes import scaled_diffuse

pytestmark = pytest.mark.mitsuba

ALPHA = 1e-3
WIDTH, HEIGHT = 48, 36
SPP = 1024


def _scenes():
    from bsdflab.scenes import scene

    return scene


def _render_ours(scene: Scene, spp: int, seed: int, **kwargs):
    result = render(scene, spp=spp, seed=seed, progress=False, **kwargs)
    return result.mean, result.variance


def _render_mitsuba(scene: Scene, spp: int, seed: int, **kwargs):
    from bsdflab.reference.mitsuba_render import render_mitsuba

    return render_mitsuba(scene, spp, seed=seed, **kwargs)


def _figure_dir(tmp_path: Path) -> Path:
    return Path(os.environ.get("BSDFLAB_TEST_FIGURES", tmp_path))


def _check(name: str, ours, theirs, tmp_path: Path, block: int = 1, labels=("bsdflab", "Mitsuba 3")):
    result = image_z_test(*ours, *theirs, alpha=ALPHA, block=block)
    if not result.passed:
        png = result.plot(_figure_dir(tmp_path) / f"{name}.png", title=f"{name}: {result.summary()}", labels=labels)
        pytest.fail(f"{name}: {result.summary()}\nfigure: {png}")
    return result


def _has_diffuse(scene: Scene) -> bool:
    return any(m.bsdf.get("type") == "diffuse" for m in scene.materials.values())


# -- scenes of our own (need only geometry) --------------------------------------------------
def _sphere_on_floor(env: Environment) -> Scene:
    return sphere_on_floor(WIDTH, HEIGHT, env)  # the validation registry's scene


def _coarse_envmap(path: Path) -> Environment:
    """A 4 x 8 lat-long map with very different rows: any disagreement on where the rows
    lie (see mitsuba_scene.mitsuba_latlong) shows at once."""
    from bsdflab.render.image_io import write_exr

    rng = np.random.default_rng(0)
    write_exr(path, rng.uniform(0.1, 3.0, (4, 8, 3)).astype(np.float32))
    return Environment("envmap", path=str(path), scale=0.8)


# -- Mitsuba against itself: the machinery works and has power --------------------------------
def test_mitsuba_seeds_agree_and_a_three_percent_albedo_change_is_detected(tmp_path):
    scene = _sphere_on_floor(Environment("sky"))
    a = _render_mitsuba(scene, SPP, seed=1)
    b = _render_mitsuba(scene, SPP, seed=2)
    _check("mitsuba-vs-mitsuba", a, b, tmp_path, labels=("Mitsuba seed 1", "Mitsuba seed 2"))
    brighter = _render_mitsuba(scaled_diffuse(scene, 1.03), SPP, seed=3)
    assert not image_z_test(*brighter, *b, alpha=ALPHA, block=2).passed


def test_variance_matches_the_scatter_between_seeds():
    """render_mitsuba's var_of_mean against the empirical variance over 16 seeds: their ratio,
    pooled over the image, is chi^2_15 / 15 per pixel, so its median is ~0.96."""
    scene = _sphere_on_floor(Environment("constant", radiance=(0.6, 0.7, 0.9))).with_resolution(16, 12)
    means = [_render_mitsuba(scene, 64, seed=100 + k)[0] for k in range(16)]
    _, var = _render_mitsuba(scene, 64, seed=99)
    ok = var > 1e-9
    ratio = np.median(np.var(means, axis=0, ddof=1)[ok] / var[ok])
    assert 0.85 < ratio < 1.08, ratio


# -- our renderer against Mitsuba ---------------------------------------------------------------
@pytest.mark.parametrize("env", ["constant", "sky", "envmap"])
def test_sphere_on_floor_matches_mitsuba(env, tmp_path):
    environment = {"constant": Environment("constant", radiance=(0.6, 0.7, 0.9)),
                   "sky": Environment("sky", scale=1.5),
                   "envmap": _coarse_envmap(tmp_path / "map.exr") if env == "envmap" else None}[env]
    scene = _sphere_on_floor(environment)
    _check(f"sphere-on-floor-{env}", _render_ours(scene, SPP, 0), _render_mitsuba(scene, SPP, 1), tmp_path)


def test_basic_materials_matches_mitsuba(tmp_path):
    scene = _scenes()("basic-materials").with_resolution(WIDTH, HEIGHT)
    theirs = _render_mitsuba(scene, SPP, seed=1, bsdflab_fallback=True)
    _check("basic-materials", _render_ours(scene, SPP, 0), theirs, tmp_path)


def test_wrong_albedo_fails_against_mitsuba():
    """Power: our render with every diffuse albedo 3 % higher must be rejected."""
    scene = _scenes()("basic-materials").with_resolution(WIDTH, HEIGHT)
    assert _has_diffuse(scene), "the power test needs a diffuse material in basic-materials"
    theirs = _render_mitsuba(scene, SPP, seed=1, bsdflab_fallback=True)
    ours = _render_ours(scaled_diffuse(scene, 1.03), SPP, 0)
    assert not image_z_test(*ours, *theirs, alpha=ALPHA, block=2).passed


@pytest.mark.parametrize("max_depth", [2, 3])
def test_smooth_dielectric_sphere_depth_matches_mitsuba(max_depth, tmp_path):
    """max_depth counts vertices as Mitsuba's does: a head-on smooth glass sphere shows only
    its front's delta reflection (R(0) = 0.04) at depth 2 in both renderers, and the light
    through it from depth 3 (tests/render/test_render_depth.py has the closed forms)."""
    ball = Shape({"type": "sphere", "center": [0, 0, 0], "radius": 1.0, "subdivisions": 64}, "glass", name="ball")
    camera = Camera(origin=(0.0, 0.0, 5.0), target=(0.0, 0.0, 0.0), fov_deg=0.05, width=8, height=8)
    scene = Scene(camera, (ball,), {"glass": Material({"type": "dielectric", "int_ior": 1.5, "ext_ior": 1.0})},
                  Environment("constant", radiance=(1.0, 1.0, 1.0)), max_depth=max_depth, rr_depth=64)
    # 8 x 8 pixels all see the centre: 4x4 blocks pool 1024 samples each, near-Gaussian means
    _check(f"glass-sphere-depth-{max_depth}", _render_ours(scene, 64, 0), _render_mitsuba(scene, 64, 1), tmp_path,
           block=4)


def test_sphere_diffuse_matches_mitsuba(tmp_path):
    scene = _scenes()("sphere", variant="diffuse").with_resolution(WIDTH, HEIGHT)
    _check("sphere-diffuse", _render_ours(scene, SPP, 0), _render_mitsuba(scene, SPP, 1), tmp_path)


def test_bumped_sphere_is_refused_by_the_mitsuba_conversion():
    from bsdflab.reference.mitsuba_scene import to_mitsuba_scene

    scene = _scenes()("sphere", variant="diffuse+bump")
    with pytest.raises(ValueError, match="scales"):
        to_mitsuba_scene(scene)


def test_furnace_matches_mitsuba(tmp_path):
    scene = _scenes()("furnace").with_resolution(WIDTH, HEIGHT)
    _check("furnace", _render_ours(scene, SPP, 0), _render_mitsuba(scene, SPP, 1, bsdflab_fallback=True), tmp_path)


# -- the table plugin ---------------------------------------------------------------------------
def _snake_table_sphere() -> Scene:
    from bsdflab.presets import xenopeltis

    request = {"type": "tabulated", "model": xenopeltis().to_dict(),
               "grid": {"n_theta_i": 6, "n_theta_o": 12, "n_phi": 7, "thickness_nm": []},
               "rel_error": 0.05, "min_samples": 256}
    return Scene(Camera(origin=(0.0, 1.4, 3.2), target=(0.0, 1.0, 0.0), fov_deg=45, width=32, height=24),
                 (Shape({"type": "sphere", "center": [0, 1, 0], "subdivisions": 32}, "snake", name="ball"),),
                 {"snake": Material(request)}, Environment("sky", scale=2.0), max_depth=4, rr_depth=3)


def test_snake_table_through_the_plugin_matches_ours(tmp_path_factory, tmp_path):
    """The snake's table material on a sphere: Mitsuba renders it through the bsdflab_table
    plugin (wavefront mode), our renderer through its own table lookup; both resolve the
    table through the same cache, so the images must agree."""
    cache = tmp_path_factory.mktemp("tables")
    scene = _snake_table_sphere()
    ours = _render_ours(scene, 512, 0, cache_dir=cache)
    theirs = _render_mitsuba(scene, 384, seed=1, cache_dir=cache)  # wavefront mode: ~3x slower
    _check("snake-table-plugin", ours, theirs, tmp_path)
