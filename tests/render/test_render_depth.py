"""What ``max_depth`` means, pinned on delta (smooth) surfaces with closed-form pixels.

``max_depth`` counts path vertices from the camera as Mitsuba 3's ``path`` integrator does
(docs/rendering.md, "What max_depth counts"): 1 = emitters seen directly, 2 = the
environment seen through one surface event (a delta reflection included), 3 = through two.

A very narrow camera (0.05 deg) looks head-on at a unit sphere in a constant unit
environment, so every pixel sees the sphere's centre at normal incidence:
- smooth dielectric (n = 1.5): depth 1 -> 0, depth 2 -> R(0), depth 3 -> R(0) + T(0)^2
  (in through the front, out through the back), T = 1 - R, R(0) = ((n - 1) / (n + 1))^2;
- a layered stack (film-coated smooth top, clear slab, black base): its only light is the
  top's delta reflection, so depth 2 (and any deeper) -> ``delta_reflectance`` x L_env.

Tolerance: two-sided z-tests at ALPHA = 1e-4 per check. For the dielectric each camera
sample is exactly 0 or 1 (Fresnel-selected delta lobe, weight 1), so the image mean over
N samples is a binomial proportion with known sd sqrt(p (1 - p) / N); for the layered case
the standard error comes from the renderer's per-pixel variance. Power: an off-by-one in
the depth cut moves the depth-2 pixel to 0 or to ~0.96 (hundreds of sd away).
"""
from __future__ import annotations

import numpy as np
import pytest

from bsdflab.bsdfs.base import from_dict
from bsdflab.render import Camera, Environment, Material, Scene, Shape, render
from bsdflab.testing import sidak_z_limit
from support.render_scenes import BLACK_LAYERED

ALPHA = 1e-4
Z = sidak_z_limit(ALPHA)
SIZE, SPP = 8, 64
N = SIZE * SIZE * SPP           # camera samples, all at the sphere's centre
IOR = 1.5
R0 = ((IOR - 1) / (IOR + 1)) ** 2


def head_on_sphere(bsdf: dict, max_depth: int) -> Scene:
    ball = Shape({"type": "sphere", "center": [0, 0, 0], "radius": 1.0, "subdivisions": 64}, material="m",
                 name="ball")
    camera = Camera(origin=(0.0, 0.0, 5.0), target=(0.0, 0.0, 0.0), up=(0.0, 1.0, 0.0), fov_deg=0.05,
                    width=SIZE, height=SIZE)
    return Scene(camera, (ball,), {"m": Material(bsdf)}, Environment("constant", radiance=(1.0, 1.0, 1.0)),
                 max_depth=max_depth, rr_depth=64, name="head-on-sphere")


DIELECTRIC = {"type": "dielectric", "int_ior": IOR, "ext_ior": 1.0}


@pytest.mark.parametrize("max_depth, expected", [(1, 0.0), (2, R0), (3, R0 + (1 - R0) ** 2)])
def test_smooth_dielectric_sphere_depth_follows_mitsuba(max_depth, expected):
    """Depth 2 shows the environment through the front's delta reflection: R(0) = 0.04,
    dark but not black; the transmitted light needs two surface events (depth 3)."""
    result = render(head_on_sphere(DIELECTRIC, max_depth), spp=SPP, seed=3, progress=False)
    mean = result.mean.mean(axis=(0, 1))
    sd = np.sqrt(expected * (1 - expected) / N)
    assert np.all(np.abs(mean - expected) <= Z * sd + 1e-12), (max_depth, mean, expected, sd)


@pytest.mark.parametrize("max_depth", [1, 2, 4])
def test_layered_smooth_top_over_black_base_shows_its_delta_reflection(max_depth):
    """A film-coated smooth top over a clear slab and a black base: the centre pixel is
    the top's delta reflectance times L_env from depth 2 on (the walk below adds nothing)."""
    expected = 0.0 if max_depth == 1 else from_dict(BLACK_LAYERED).delta_reflectance(np.array([0.0, 0.0, 1.0]))[0]
    result = render(head_on_sphere(BLACK_LAYERED, max_depth), spp=SPP, seed=4, progress=False)
    mean = result.mean.mean(axis=(0, 1))
    err = np.sqrt(result.variance.sum(axis=(0, 1))) / (SIZE * SIZE)
    assert np.all(np.abs(mean - expected) <= Z * err + 1e-12), (max_depth, mean, expected, err)
    if max_depth > 1:
        assert np.all(expected > 0.1)  # the case is not vacuous: a clearly visible reflection
