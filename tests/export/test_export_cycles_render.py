"""The exported .blend in Cycles against bsdflab's own renderer, in the same scene.

Scene (tests/support/cycles_spheres.py): the export's unit sphere, black body, constant
white world, now through a pinhole camera both renderers hold (distance 5, 26 deg), pixels
box-filtered over their area in both. A smooth guanine film (1.83, 400 nm) on keratin
(1.5515) is exported to Blender (fitted for Cycles' thin film); Cycles renders the exported
scene (seeds 0 and 1); bsdflab's path tracer renders the same sphere with

1. Cycles' thin-film model at the fitted parameters, as the comparison BSDF
   ``cycles_thin_film_comparison`` (reference/approximations/cycles_bsdf.py): per 4 x 4
   block the images agree within z = 4 standard deviations of both renderers' noise
   (bsdflab's per-pixel variance; Cycles' from the two seeds) plus 0.003, the model's
   measured distance from Cycles' pixels (test_cycles_thin_film.py). z = 4: alpha 6e-5 per
   block and channel, Sidak over the 52 blocks x 3 channels ~ 0.01. This proves the mapping
   into Blender, through a path tracer rather than a closed form;
2. bsdflab's exact film on the same opaque base (``model="exact"``): Delta E00 between
   Cycles' blocks and these agrees with the report's map at the nominal thickness
   (interpolated in angle) within 0.4, as test_export_cycles_crosscheck.py.

Blocks are kept within 60 deg of normal incidence (the silhouette's pixels mix in the
world and the two tessellations differ there). Mutation tried: Thin Film IOR + 0.03 in the
Cycles scene fails (1).
"""
from __future__ import annotations

import numpy as np
import pytest

import bsdflab.reference.approximations.cycles_bsdf  # noqa: F401  (registers the comparison BSDF)
from bsdflab.reference.approximations.study import delta_e00
from support.cycles_spheres import blocks, bsdflab_sphere, perspective_cosines, render_perspective

SIZE, BLOCK, SPP = 48, 4, 16


@pytest.fixture(scope="module")
def renders(tmp_path_factory, film_blender_export):
    report, _ = film_blender_export
    folder = tmp_path_factory.mktemp("cycles_render")
    p = {k: v["value"] for k, v in report["parameters"].items()}
    cycles = render_perspective(p, str(folder), SIZE, SPP)
    model = {"type": "cycles_thin_film_comparison", "film_ior": p["film_ior"], "base_ior": p["base_ior"],
             "film_thickness_nm": p["film_thickness_nm"]}
    exact = {"type": "cycles_thin_film_comparison", "film_ior": 1.83, "base_ior": 1.5515, "film_thickness_nm": 400.0,
             "model": "exact"}
    return report, cycles, bsdflab_sphere(model, SIZE, SPP), bsdflab_sphere(exact, SIZE, SPP, seed=1)


def _blocks(img):
    return blocks(img, BLOCK)


def _region():
    cos = perspective_cosines(SIZE)
    keep = np.isfinite(cos) & (np.nan_to_num(cos) >= np.cos(np.radians(60.0)))
    return np.nan_to_num(cos, nan=1.0), keep.reshape(SIZE // BLOCK, BLOCK, SIZE // BLOCK, BLOCK).all(axis=(1, 3))


def test_bsdflab_renders_what_cycles_renders_from_the_export(renders):
    """Mutation: Thin Film IOR + 0.03 in the exported Cycles scene (export/blender.py) fails it."""
    _, (a, b), model, _ = renders
    _, full = _region()
    cycles = _blocks(0.5 * (a + b))
    var_c = ((_blocks(a) - _blocks(b)) / 2.0) ** 2
    var_b = _blocks(model.variance) / BLOCK**2
    diff = np.abs(cycles - _blocks(model.mean))[full]
    assert full.sum() >= 48
    assert np.all(diff <= 4.0 * np.sqrt(var_c + var_b)[full] + 0.003), diff.max()


def test_cycles_against_bsdflab_exact_render_is_the_reported_error(renders):
    report, (a, b), _, exact = renders
    cos, full = _region()
    measured = delta_e00(_blocks(0.5 * (a + b))[full], _blocks(exact.mean)[full])
    angle = np.degrees(np.arccos(np.clip(_blocks(cos[..., None])[..., 0][full], -1, 1)))
    e = report["delta_e00"]
    predicted = np.interp(angle, e["angles_deg"], np.array(e["map"])[:, len(e["thickness_scales"]) // 2])
    assert np.all(np.abs(measured - predicted) <= 0.4), np.abs(measured - predicted).max()
