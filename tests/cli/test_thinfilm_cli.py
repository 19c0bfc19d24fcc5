"""`bsdflab thinfilm` as a user runs it, and the aliasing it exists to show."""
import os
import subprocess
import sys

import numpy as np
import pytest

from bsdflab.cli.main import main
from bsdflab.optics import FilmLayer, FilmStack, film_reflectance
from bsdflab.plots.film_colour import delta_e_2000, reflectance, spectral_rgb, three_wavelength_colour
from bsdflab.presets import AIR_IOR, GUANINE_IOR, KERATIN_IOR_550
from bsdflab.spectra import THREE_WAVELENGTHS_NM, three_wavelength_rgb

BSDFLAB = [sys.executable, "-m", "bsdflab.cli.main"]
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def run(*args):
    return subprocess.run([*BSDFLAB, *args], capture_output=True, text=True, timeout=120)


def snake_film(d_nm):
    return (AIR_IOR, GUANINE_IOR, d_nm, KERATIN_IOR_550)


# -- the command ----------------------------------------------------------------------

def test_01_help():
    r = run("thinfilm", "--help")
    assert r.returncode == 0 and "usage:" in r.stdout and "--preset-stack" in r.stdout


def test_02_writes_a_png_and_a_summary(tmp_path):
    out = tmp_path / "sub" / "film.png"
    r = run("thinfilm", "--thickness", "300", "--out", str(out))
    assert r.returncode == 0, r.stderr
    assert out.read_bytes()[:8] == PNG_MAGIC
    assert not [p for p in os.listdir(out.parent) if p.endswith(".tmp")]
    assert "spectral sRGB" in r.stdout and "3-wavelength" in r.stdout


def test_02b_preset_stack(tmp_path, capsys):
    """In-process (the subprocess path is test_02): the stack variant's own code path."""
    out = tmp_path / "stack.png"
    assert main(["thinfilm", "--preset-stack", "--thickness-range", "400", "1000",
                 "--out", str(out)]) == 0
    assert out.read_bytes()[:8] == PNG_MAGIC
    assert "5 platelets" in capsys.readouterr().out
    assert os.listdir(tmp_path) == ["stack.png"]


@pytest.mark.parametrize("args, match", [
    (["--thickness", "-5"], "--thickness must be >= 0"),
    (["--film-ior", "0"], "--film-ior must be > 0"),
    (["--substrate-ior", "-1.5"], "--substrate-ior must be > 0"),
    (["--ext-ior", "nan"], "--ext-ior must be finite"),
    (["--thickness-range", "800", "200"], "--thickness-range MAX must be > 800"),
    (["--thickness-range", "-10", "200"], "--thickness-range MIN must be >= 0"),
    (["--thickness-range", "0", "100000"], "reduce --thickness-range"),
    (["--preset-stack", "--thickness", "300"], "--preset-stack"),
])
def test_03_bad_input_is_a_message_not_a_traceback(tmp_path, args, match):
    out = tmp_path / "x.png"
    r = run("thinfilm", *args, "--out", str(out))
    assert r.returncode == 2, r.stderr
    assert match in r.stderr and "Traceback" not in r.stderr
    assert not out.exists() and not os.listdir(tmp_path)


# -- the aliasing ---------------------------------------------------------------------

def test_04_three_wavelengths_alias_a_thick_film():
    """1200 nm of guanine has ~70 nm fringes: the spectral colour is near-grey at every
    angle up to 60 deg, while the three samples land on peaks and troughs by chance.
    CIEDE2000 of about 1-2 is just noticeable; we demand > 10 at each angle."""
    theta = np.radians(np.arange(0.0, 61.0, 10.0))
    spectral = spectral_rgb(snake_film(1200.0), theta)
    three = three_wavelength_colour(snake_film(1200.0), theta)
    assert np.all(delta_e_2000(spectral, three) > 10.0)
    assert np.ptp(spectral, axis=-1).max() < 0.01  # spectral: R, G, B within 0.01: grey


def test_05_flat_spectrum_gives_the_same_colour():
    """Zero thickness leaves a bare interface between constant indices: R is the same at
    every wavelength, and the spectral matrix maps a constant v to (v, v, v) exactly (it is
    adapted so that white is (1, 1, 1)), so the two agree to rounding: 1e-12."""
    theta = np.radians(np.arange(0.0, 90.0, 5.0))
    spectral = spectral_rgb(snake_film(0.0), theta)
    three = three_wavelength_colour(snake_film(0.0), theta)
    np.testing.assert_allclose(spectral, three, rtol=0, atol=1e-12)


def test_06_three_wavelength_rgb_is_the_samples_in_order():
    values = film_reflectance(snake_film(400.0), np.asarray(THREE_WAVELENGTHS_NM), 0.3)
    assert THREE_WAVELENGTHS_NM == (650.0, 510.0, 475.0)
    np.testing.assert_array_equal(three_wavelength_rgb(values), values)
    with pytest.raises(ValueError, match="axis of 3"):
        three_wavelength_rgb([0.1, 0.2])


def test_07_stack_thickness_sweep_equals_scaled_layers():
    """The stack sweep uses R(lambda; s d) = R(lambda / s; d); check it against stacks
    rebuilt with scaled layers."""
    layers = [(GUANINE_IOR, 80.0), (1.33, 100.0), (GUANINE_IOR, 80.0)]
    stack = FilmStack(AIR_IOR, [FilmLayer(n, d) for n, d in layers], KERATIN_IOR_550)
    wl, theta = np.linspace(380.0, 780.0, 41), np.radians(35.0)
    totals = np.array([0.0, 130.0, 260.0, 520.0])
    swept = reflectance(stack, wl[None, :], theta, totals[:, None])
    for total, row in zip(totals, swept, strict=True):
        s = total / 260.0
        scaled = FilmStack(AIR_IOR, [FilmLayer(n, s * d) for n, d in layers], KERATIN_IOR_550)
        np.testing.assert_allclose(row, film_reflectance(scaled, wl, theta), atol=1e-12, rtol=0)
