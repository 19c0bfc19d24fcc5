"""Point, spot and directional lights against Mitsuba 3's ``point``, ``spot`` and
``directional`` emitters (reference/mitsuba_scene.py converts them with the same parameters),
in RGB and in spectral mode.

The scene is the image cross-checks' red ball on a grey floor (the validation registry's
``sphere_on_floor``) with its lamp taken away, lit by one light at a time, and then by all
three together with the lamp (an area light) and an environment (a lat-long map in RGB, a
constant colour in spectral mode, where lat-long maps do not convert): with several emitters
both renderers pick one per next-event estimate and weight by MIS, each in its own way, so
only correct light-selection probabilities and delta-light weights make the images agree.

Method as in test_mitsuba_render.py: ``image_z_test`` per pixel-channel with both images'
variances of the mean, Sidak-corrected over all pixel-channels at family-wise ALPHA = 1e-3,
fixed seeds. Power: our point light 3 % brighter, and our spot with a cutoff 2 deg narrower,
are rejected against Mitsuba's unchanged image.
"""
from __future__ import annotations

import os
from dataclasses import replace
from functools import cache
from pathlib import Path

import numpy as np
import pytest

from bsdflab.render import Environment, Scene, render
from bsdflab.testing import image_z_test
from bsdflab.validation.checks.renderer import sphere_on_floor

pytestmark = pytest.mark.mitsuba

ALPHA = 1e-3
WIDTH, HEIGHT = 32, 24
SPP = 512
POINT = {"type": "point", "position": [1.2, 2.2, 1.0], "intensity": [6.0, 5.0, 4.0]}
SPOT = {"type": "spot", "position": [-1.0, 2.5, 1.5], "direction": [1.0, -1.5, -1.5], "intensity": 14.0,
        "cutoff_angle_deg": 25.0, "beam_width_deg": 15.0}
DIRECTIONAL = {"type": "directional", "direction": [0.4, -1.0, -0.3], "irradiance": [1.2, 1.1, 1.0]}
# A light whose colour is a spectrum (rising to the red): spectral mode uses its bins as they
# are, Mitsuba gets them as the same step spectrum; RGB mode uses its RGB.
_WL = np.arange(380.0, 781.0, 5.0)
SPECTRAL_POINT = {**POINT, "intensity": {"type": "tabulated", "wavelengths": _WL.tolist(),
                                         "values": np.linspace(1.0, 9.0, len(_WL)).tolist()}}
# The sun preset without its sky and with a sharp disc (Mitsuba has no soft sun): its RGB in
# RGB mode, its atmospheric spectrum (bsdflab.render.sky.sun_spectrum) in spectral mode.
SUN = {"type": "sun", "elevation_deg": 25.0, "azimuth_deg": 40.0, "turbidity": 4.0, "scale": 0.01,
       "angular_diameter_deg": 0.0, "sky": False}
LIGHTS = {"point": [POINT], "spot": [SPOT], "directional": [DIRECTIONAL], "mixed": [POINT, SPOT, DIRECTIONAL],
          "spectral-point": [SPECTRAL_POINT], "sun": [SUN]}


def _coarse_envmap(folder: Path) -> Environment:
    from bsdflab.render.image_io import write_exr

    path = folder / "lights-map.exr"
    if not path.exists():
        rng = np.random.default_rng(0)
        write_exr(path, rng.uniform(0.05, 0.6, (4, 8, 3)).astype(np.float32))
    return Environment("envmap", path=str(path), scale=1.0)


def _scene(name: str, spectral: bool, folder: Path) -> Scene:
    mixed = name == "mixed"
    env = Environment()
    if mixed:
        env = Environment("constant", radiance=(0.15, 0.2, 0.3)) if spectral else _coarse_envmap(folder)
    base = sphere_on_floor(WIDTH, HEIGHT, env)
    shapes = base.shapes if mixed else tuple(s for s in base.shapes if s.name != "lamp")
    return replace(base, shapes=shapes, lights=LIGHTS[name])


def _ours(scene: Scene, spectral: bool, seed: int = 0):
    r = render(scene, spp=SPP, seed=seed, progress=False, spectral=spectral)
    return r.mean, r.variance


@cache
def _theirs(name: str, spectral: bool, folder: str):
    from bsdflab.reference.mitsuba_render import render_mitsuba

    return render_mitsuba(_scene(name, spectral, Path(folder)), SPP, seed=1, spectral=spectral)


@pytest.fixture(scope="module")
def folder(tmp_path_factory) -> str:
    return str(tmp_path_factory.mktemp("lights"))


def _check(label: str, ours, theirs, tmp_path: Path):
    result = image_z_test(*ours, *theirs, alpha=ALPHA)
    if not result.passed:
        figures = Path(os.environ.get("BSDFLAB_TEST_FIGURES", tmp_path))
        png = result.plot(figures / f"{label}.png", title=f"{label}: {result.summary()}",
                          labels=("bsdflab", "Mitsuba 3"))
        pytest.fail(f"{label}: {result.summary()}\nfigure: {png}")


@pytest.mark.parametrize("spectral", [False, True], ids=["rgb", "spectral"])
@pytest.mark.parametrize("name", ["point", "spot", "directional", "mixed", "spectral-point", "sun"])
def test_lights_match_mitsuba(name, spectral, folder, tmp_path):
    scene = _scene(name, spectral, Path(folder))
    _check(f"lights-{name}-{'spectral' if spectral else 'rgb'}", _ours(scene, spectral),
           _theirs(name, spectral, folder), tmp_path)


@pytest.mark.parametrize("spectral", [False, True], ids=["rgb", "spectral"])
def test_wrong_lights_are_rejected(spectral, folder):
    """Power: a point light 3 % brighter and a spot whose cutoff is 2 deg narrower than
    Mitsuba's must fail (2 x 2 blocks, as the other power checks)."""
    scene = _scene("point", spectral, Path(folder))
    brighter = replace(scene, lights=[{**POINT, "intensity": [1.03 * x for x in POINT["intensity"]]}])
    assert not image_z_test(*_ours(brighter, spectral), *_theirs("point", spectral, folder), alpha=ALPHA,
                            block=2).passed
    scene = _scene("spot", spectral, Path(folder))
    narrower = replace(scene, lights=[{**SPOT, "cutoff_angle_deg": 23.0}])
    assert not image_z_test(*_ours(narrower, spectral), *_theirs("spot", spectral, folder), alpha=ALPHA,
                            block=2).passed


def test_soft_suns_are_refused_and_the_sun_sky_goes_over_as_a_map(folder):
    from bsdflab.reference.mitsuba_scene import to_mitsuba_scene

    soft = replace(_scene("point", False, Path(folder)),
                   lights=[{**DIRECTIONAL, "angular_diameter_deg": 2.0}])
    with pytest.raises(ValueError, match="angular diameter"):
        to_mitsuba_scene(soft)
    sun = replace(_scene("point", False, Path(folder)), lights=[{"type": "sun", "angular_diameter_deg": 0.0}])
    assert to_mitsuba_scene(sun)["environment"]["type"] == "envmap"  # RGB: the sky goes over as a map
