"""Spectral mode (render(spectral=True)): paths carry the 81 bins of the default grid, and
spectra become sRGB only when light reaches the camera.

* A film-coated mirror in a coloured constant environment, seen by a very narrow camera:
  every camera ray reflects once (delta) into the environment, so the pixel is a closed
  form, sum_l W[:, l] R(l, theta) E(l) with E the environment's spectral lift, against
  which spectral mode is checked; RGB mode gives (W R) * e instead, and the two closed
  forms differ by far more than the tolerance (so the check can tell them apart).
  Tolerance: the camera's 0.05 deg field of view changes theta by < 5e-4 rad across the
  image, which moves R by < 1e-4 (|dR/dtheta| < 0.2 on this film); 1e-3 bounds both that
  and float rounding.
* A grey world (grey Diffuse, grey lights): every spectral path's bins are equal, so the
  spectral image equals the RGB image for the same seed, up to the basis' 1e-5 deviation
  from a partition of unity.
* Thread-count independence of spectral images (subprocesses with 1 and 2 threads).
* A Diffuse with a *tabulated* reflectance spectrum keeps that spectrum (regression: it was
  rendered with the lift of its RGB, U W R, a different spectrum).
"""
from __future__ import annotations

import numpy as np
import pytest

from bsdflab import Conductor
from bsdflab.render import Camera, Environment, Material, Scene, Shape, render
from bsdflab.spectra import DEFAULT_WAVELENGTHS, rgb_to_spectrum, srgb_weights
from support.render_scenes import (
    ENV_RGB,
    FILM,
    FILM_TOP,
    THETA,
    film_mirror_scene,
    grey_world,
    tabulated_film_mirror_scene,
)
from support.thread_images import images_per_thread_count


def film_reflectance(wavelengths):
    """R(lambda) of the film on gold at THETA from the Python model (one wi per channel set)."""
    wi = np.array([[np.sin(THETA), 0.0, np.cos(THETA)]])
    # A smooth conductor reflects with probability 1: the sample weight is R per channel.
    return Conductor(material="Au", film=FILM).sample(wi, wavelengths=wavelengths, seed=0).weight[0]


def test_01_spectral_film_mirror_matches_the_spectral_closed_form():
    wl = DEFAULT_WAVELENGTHS
    W = srgb_weights(wl)
    R = film_reflectance(wl)
    E = rgb_to_spectrum(np.array(ENV_RGB), wl)
    expected_spectral = W @ (R * E)
    expected_rgb = (W @ R) * np.array(ENV_RGB)
    assert np.max(np.abs(expected_spectral - expected_rgb)) > 20e-3  # the check can fail
    spectral = render(film_mirror_scene(), spp=4, seed=3, progress=False, spectral=True)
    rgb = render(film_mirror_scene(), spp=4, seed=3, progress=False)
    assert np.all(np.abs(spectral.mean - expected_spectral) < 1e-3), (spectral.mean[0, 0], expected_spectral)
    assert np.all(np.abs(rgb.mean - expected_rgb) < 1e-3), (rgb.mean[0, 0], expected_rgb)
    assert spectral.settings["mode"] == "spectral"


def test_02_grey_world_spectral_equals_rgb_to_round_off():
    a = render(grey_world(), spp=8, seed=4, progress=False, spectral=True)
    b = render(grey_world(), spp=8, seed=4, progress=False)
    assert np.max(b.mean) > 0.05
    # Mallett & Yuksel's basis sums to 1 within 1e-5 per bin (not exactly), and a path lifts
    # at most max_depth + 1 = 7 RGB values: |spectral - rgb| <= 7e-5 relative (1e-4 allowed).
    # (Russian roulette decisions could flip on a 1e-5 change of a survival probability;
    # with this seed none does.)
    assert np.allclose(a.mean, b.mean, rtol=1e-4, atol=1e-9), np.max(np.abs(a.mean - b.mean))


def test_03_spectral_image_does_not_depend_on_thread_count(tmp_path):
    """A 40 x 40 image is 9 tiles of 16 x 16 (the renderer's tile), handed to whichever thread
    is free, so the 2-thread run really splits every pass (one tile would run on one thread
    whatever the setting)."""
    out = images_per_thread_count(tmp_path, "from support.render_scenes import grey_world; "
                                  "from bsdflab.render import render",
                                  "render(grey_world(size=40), spp=2, seed=2, progress=False, spectral=True).mean")
    assert np.array_equal(out["1"], out["2"])


def test_04_bad_spectral_flag():
    with pytest.raises(ValueError, match="spectral"):
        render(grey_world(size=4), spp=1, progress=False, spectral="yes")


def test_05_tabulated_diffuse_reflectance_keeps_its_own_spectrum():
    """A narrow-band diffuse plate under a blue constant sky, seen straight down by a
    narrow camera with one bounce: the pixel is sum_l W[:, l] R(l) E(l) (a diffuse plate
    under a uniform sky reflects rho times the sky; the plate hides nothing above it).
    Tolerance: 5 standard errors of the image mean (the render's own variance; 16 pixels
    x 64 spp) -- the old lift of R's RGB is off by 0.065 in R, > 40 of them."""
    wl = DEFAULT_WAVELENGTHS
    R = 0.05 + 0.9 * np.exp(-0.5 * ((wl - 500.0) / 15.0) ** 2)
    plate = Shape({"type": "rectangle", "center": [0, 0, 0], "normal": [0, 1, 0], "size": [1000, 1000]},
                  material="plate", name="plate")
    camera = Camera(origin=(0.0, 1.0, 0.0), target=(0.0, 0.0, 0.0), up=(0.0, 0.0, 1.0), fov_deg=1.0,
                    width=4, height=4)
    bsdf = {"type": "diffuse", "reflectance": {"type": "tabulated", "wavelengths": wl.tolist(), "values": R.tolist()}}
    scene = Scene(camera, (plate,), {"plate": Material(bsdf)}, Environment("constant", radiance=ENV_RGB),
                  max_depth=2, name="narrow-band-plate")
    r = render(scene, spp=64, seed=1, progress=False, spectral=True)
    W, E = srgb_weights(wl), rgb_to_spectrum(np.array(ENV_RGB), wl)
    expected, old = W @ (R * E), W @ (rgb_to_spectrum(W @ R, wl) * E)
    mean, err = r.mean.mean(axis=(0, 1)), np.sqrt(r.variance.sum(axis=(0, 1))) / 16
    assert np.all(np.abs(mean - expected) < 5 * err), (mean, expected, err)
    assert np.max(np.abs(old - expected) / err) > 10  # the old spectrum would fail


# -- tables: a spectral render reads a spectral table ----------------------------------------


def test_06_spectral_render_of_a_table_uses_the_spectral_table(tmp_path):
    """Spectral mode builds (and caches) a table of the 81 bins, so the film's spectrum
    multiplies the sky's bin by bin: the pixel is W (R E), the closed form of test_01 for
    the top film alone. The RGB table lifted back to bins (what spectral mode did before)
    gives W (U (W R) . E) instead, which differs by more than the tolerance (checked)."""
    from bsdflab.render.build import resolve_bsdf

    wl = DEFAULT_WAVELENGTHS
    W = srgb_weights(wl)
    wi = np.array([[np.sin(THETA), 0.0, np.cos(THETA)]])
    from bsdflab.bsdfs.base import from_dict

    # A smooth dielectric picks reflection or transmission: a reflected sample's weight x
    # its probability is R per channel.
    b = from_dict(FILM_TOP).sample(np.tile(wi, (64, 1)), wavelengths=wl, seed=5)
    k = int(np.flatnonzero(b.wo[:, 2] > 0)[0])
    R = b.weight[k] * b.pdf[k]
    E = rgb_to_spectrum(np.array(ENV_RGB), wl)
    expected = W @ (R * E)
    lifted = W @ (rgb_to_spectrum(W @ R, wl) * E)
    assert np.max(np.abs(expected - lifted)) > 5e-3  # the check can tell the two apart

    scene = tabulated_film_mirror_scene()
    table_dict = scene.materials["film"].bsdf
    spectral_table = resolve_bsdf(table_dict, cache_dir=tmp_path, spectral=True)
    rgb_table = resolve_bsdf(table_dict, cache_dir=tmp_path)
    assert len(spectral_table.table.channels) == len(wl) and rgb_table.table.channels == ("R", "G", "B")
    assert len(list(tmp_path.rglob("*.exr"))) == 2  # two cache entries

    spectral = render(scene, spp=4, seed=3, progress=False, spectral=True, cache_dir=tmp_path)
    # Same 1e-3 tolerance as test_01 (the camera's field of view and float rounding).
    assert np.all(np.abs(spectral.mean - expected) < 1e-3), (spectral.mean[0, 0], expected, lifted)
    rgb = render(scene, spp=4, seed=3, progress=False, cache_dir=tmp_path)
    assert np.all(np.abs(rgb.mean - (W @ R) * np.array(ENV_RGB)) < 1e-3)
