"""The stored colour-science arrays of the default grid (bsdflab/spectra/colour_precomputed.py)
equal what colour-science computes now, bit for bit, and a render uses them without
importing colour."""
from __future__ import annotations

import subprocess
import sys

import numpy as np

from bsdflab.spectra import (
    DEFAULT_WAVELENGTHS,
    colour_precomputed,
    colour_weights,
    rgb_to_spectrum,
    sensor_model,
    srgb_weights,
)


def test_the_stored_arrays_are_colour_sciences_bit_for_bit():
    """A colour-science upgrade that moves any value fails here, naming the command that
    regenerates the file. Mutation: one CMF value off by 1 ulp in the file fails it."""
    now, kept = colour_weights.precomputed_arrays(), colour_precomputed.stored()
    for name in colour_precomputed.NAMES:
        assert now[name].shape == kept[name].shape, name
        assert np.array_equal(now[name], kept[name]), (
            f"{name} differs from colour-science's: regenerate with "
            "python -c 'from bsdflab.spectra.colour_weights import store_precomputed; store_precomputed()'")


def test_the_default_grid_takes_the_stored_arrays_and_others_colour_science():
    grid = tuple(float(x) for x in DEFAULT_WAVELENGTHS)
    assert colour_precomputed.covers(grid)
    assert sensor_model(DEFAULT_WAVELENGTHS).cmf is colour_precomputed.stored()["cmf"]
    other = np.linspace(400.0, 700.0, 31)
    assert not colour_precomputed.covers(tuple(other))
    assert not colour_precomputed.covers(grid[:-1])
    # another grid is computed: the weights of a coarser grid still map white to (1, 1, 1)
    assert np.allclose(srgb_weights(other).sum(axis=1), 1.0, rtol=0, atol=1e-12)
    assert np.allclose(srgb_weights(DEFAULT_WAVELENGTHS).sum(axis=1), 1.0, rtol=0, atol=1e-12)
    # another colour space is computed too, never the stored default's arrays
    space = colour_weights.ColourSpace(illuminant="A")
    assert sensor_model(DEFAULT_WAVELENGTHS, space).cmf is not colour_precomputed.stored()["cmf"]
    assert np.allclose(rgb_to_spectrum([0.2, 0.5, 0.8], DEFAULT_WAVELENGTHS) @ srgb_weights(DEFAULT_WAVELENGTHS).T,
                       [0.2, 0.5, 0.8], rtol=0, atol=2e-3)


def test_a_render_imports_no_colour(tmp_path):
    """The point of the stored arrays: a render of materials (diffuse, conductor, the
    snake's table) and its PNG cost no colour-science import."""
    code = ("import sys; from bsdflab.cli.main import main; "
            f"sys.argv = ['bsdflab', 'render', 'basic-materials', '--width', '8', '--height', '6', '--spp', '1', "
            f"'--out', {str(tmp_path / 'a.exr')!r}, '--quiet']\n"
            "try:\n    main()\nexcept SystemExit:\n    pass\n"
            "print('colour imported' if 'colour' in sys.modules else 'no colour')")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600)
    assert out.stdout.strip().splitlines()[-1] == "no colour", out.stdout + out.stderr
    assert (tmp_path / "a.png").exists()
