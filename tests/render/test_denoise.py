"""`bsdflab render --denoise`: a denoised preview (Intel Open Image Denoise through pyoidn,
guided by first-hit albedo and normal images) written beside the EXR, only on request,
with the EXR's pixels bit-identical with and without it."""
from __future__ import annotations

import numpy as np
import pytest

from bsdflab.cli.main import main
from bsdflab.render import read_exr, render
from bsdflab.scenes import scene
from support.png_check import assert_png_shows_exr

ARGS = ["render", "basic-materials", "--width", "48", "--height", "36", "--spp", "4", "--quiet"]


def test_01_preview_only_on_request_and_exr_unchanged(tmp_path):
    plain, denoised = tmp_path / "plain.exr", tmp_path / "den.exr"
    assert main([*ARGS, "--out", str(plain)]) == 0
    assert not (tmp_path / "plain.denoised.exr").exists() and not (tmp_path / "plain.denoised.png").exists()
    assert main([*ARGS, "--out", str(denoised), "--denoise"]) == 0
    a, b = read_exr(plain), read_exr(denoised)
    assert a.tobytes() == b.tobytes()  # bit-identical pixels
    preview = read_exr(tmp_path / "den.denoised.exr")
    assert preview.shape == a.shape and np.all(np.isfinite(preview))
    # the preview PNG shows the denoised EXR, not the noisy one (mutation: PNG from `image`)
    assert_png_shows_exr(tmp_path / "den.denoised.png", preview)
    assert_png_shows_exr(tmp_path / "den.png", b)
    assert not np.array_equal(preview, a)


def test_02_denoised_preview_is_closer_to_a_converged_image():
    """The preview is a denoiser's output, not a copy: at 4 spp its error against a 256-spp
    image is smaller than the noisy image's (a weak, robust property of any denoiser)."""
    from bsdflab.render.denoise import denoise

    s = scene("basic-materials", width=48, height=36)
    noisy = render(s, spp=4, seed=1, progress=False, aovs=True)
    reference = render(s, spp=256, seed=2, progress=False)
    err_noisy = np.mean((noisy.mean - reference.mean) ** 2)
    err_denoised = np.mean((denoise(noisy) - reference.mean) ** 2)
    assert err_denoised < err_noisy
    albedo, normal = noisy.aovs["albedo"], noisy.aovs["normal"]
    assert albedo.min() >= 0 and albedo.max() <= 1
    lengths = np.linalg.norm(normal, axis=-1)
    assert np.all((np.abs(lengths - 1) < 1e-6) | (lengths == 0))


def test_03_denoise_without_aovs_is_a_clear_error():
    from bsdflab.render.denoise import denoise

    r = render(scene("basic-materials", width=8, height=6), spp=1, progress=False)
    with pytest.raises(ValueError, match="aovs"):
        denoise(r)
