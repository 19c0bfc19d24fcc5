"""The Cycles thin-film model (reference/approximations/cycles.py) against real Cycles renders.

Scene (tests/support/cycles_spheres.py): a smooth Principled sphere, black base, IOR 1.5515,
Thin Film IOR 1.83 at 250 / 400 / 1100 nm, constant white world, orthographic camera,
CPU, 4 samples, 48 x 48 pixels. Statistic: per 4 x 4 block of sphere pixels all within
theta <= 42 deg, the difference between Cycles and the model, against a tolerance of
4 sigma + 0.003: sigma is the seed-to-seed scatter of the block mean (two seeds; the
scene is nearly deterministic), 0.003 covers Cycles' float32 table (512 entries, linear
interpolation) and the pixel footprint (the normal changes across a pixel; beyond
~50 deg that footprint, not the model, dominates: 0.0065 at 50 deg, 0.017 at 60 deg per
pixel, so those pixels are left out). alpha per block ~ 6e-5 (4 sigma, normal), Sidak
over ~200 block-channel tests: family alpha ~ 0.01. Power (mutations that must fail): the
MaterialX Belcour-Barla model (the old label's claim), and the Cycles model with the CMFs
resampled in frequency without the 1 / nu^2 Jacobian.
"""
from __future__ import annotations

import numpy as np
import pytest

from bsdflab.reference.approximations import belcour_barla_rgb
from bsdflab.reference.approximations.cycles import cycles_thin_film_rgb
from support.cycles_spheres import pixel_cosines, render_spheres_seeds

THICKNESSES = (250.0, 400.0, 1100.0)
PARAMS = {"base_color": (0.0, 0.0, 0.0), "roughness": 0.0, "base_ior": 1.5515, "film_ior": 1.83,
          "film_thickness_nm": 400.0}
SIZE, BLOCK = 48, 4


@pytest.fixture(scope="module")
def renders(tmp_path_factory):
    a, b = render_spheres_seeds(PARAMS, THICKNESSES, str(tmp_path_factory.mktemp("s")), SIZE, seeds=(0, 1))
    return a, b


def _blocks(img):
    t, h, w, c = img.shape
    return img.reshape(t, h // BLOCK, BLOCK, w // BLOCK, BLOCK, c).mean(axis=(2, 4))


def _failures(renders, model):
    """(share of block-channel tests failing, worst |difference|, number of tests)."""
    a, b = renders
    cos = pixel_cosines(SIZE)
    predicted = np.stack([model(1.0, 1.83, 1.5515, d, np.nan_to_num(cos, nan=1.0)) for d in THICKNESSES])
    keep = np.isfinite(cos) & (np.nan_to_num(cos) >= np.cos(np.radians(42.0)))
    full = keep.reshape(SIZE // BLOCK, BLOCK, SIZE // BLOCK, BLOCK).all(axis=(1, 3))
    mean = 0.5 * (_blocks(a) + _blocks(b))
    sigma = np.abs(_blocks(a) - _blocks(b)) / 2.0
    diff = np.abs(mean - _blocks(predicted))[:, full]
    tol = 4.0 * sigma[:, full] + 0.003
    return float(np.mean(diff > tol)), float(diff.max()), int(diff.size)


def test_cycles_model_matches_cycles_renders(renders):
    """Mutation: cycles_thin_film_rgb without the 1 / nu^2 Jacobian by default fails it."""
    share, worst, n = _failures(renders, cycles_thin_film_rgb)
    assert n > 100
    assert share == 0.0, (share, worst)


def test_materialx_belcour_barla_is_not_what_cycles_computes(renders):
    share, worst, _ = _failures(renders, belcour_barla_rgb)
    assert share > 0.2 and worst > 0.01


def test_the_other_cmf_resampling_is_not_what_cycles_computes(renders):
    share, worst, _ = _failures(renders, lambda *a: cycles_thin_film_rgb(*a, jacobian=False))
    assert share > 0.05 and worst > 0.005
