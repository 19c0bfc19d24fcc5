"""bsdflab's sRGB curve equals colour-science's, bit for bit (PNG pixels must not move)."""
from __future__ import annotations

import subprocess
import sys

import colour
import numpy as np

from bsdflab.spectra.srgb_curve import srgb_encode


def test_equals_colour_science_bit_for_bit():
    """Every float32 pixel value a PNG is made from: a dense sweep of [0, 1], the knee's
    neighbours and the ends. Mutations: the knee at 0.04045 (the decoding side's), or the
    exponent 1/2.2, fail it."""
    x = np.concatenate([np.linspace(0, 1, 200_001, dtype=np.float32),
                        np.nextafter(np.float32(0.0031308), [-1, 1]).astype(np.float32),
                        np.float32([0.0031308, 0.0, 1.0, 1e-30])])
    ours = srgb_encode(x)
    theirs = colour.cctf_encoding(x, function="sRGB")
    assert ours.dtype == theirs.dtype == np.float64
    assert np.array_equal(ours, theirs)
    assert np.array_equal(np.round(ours * 255), np.round(theirs * 255))


def test_writing_a_png_does_not_import_colour(tmp_path):
    """The point of the module: a render's PNG costs no colour-science import."""
    code = ("import sys, numpy as np; from bsdflab.render.image_io import write_png; "
            f"write_png({str(tmp_path / 'a.png')!r}, np.full((4, 4, 3), 0.5, np.float32)); "
            "print('colour' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False", out.stderr
