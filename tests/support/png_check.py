"""The PNG beside a render, checked against its EXR with the sRGB curve written out here
(IEC 61966-2-1), independent of the code under test (colour-science's encoding)."""
from __future__ import annotations

import numpy as np


def srgb_8bit(linear: np.ndarray) -> np.ndarray:
    """Linear RGB -> 8-bit sRGB: clip to [0, 1], the piecewise sRGB transfer curve, round."""
    a = np.clip(np.nan_to_num(np.asarray(linear, np.float64)), 0.0, 1.0)
    encoded = np.where(a <= 0.0031308, 12.92 * a, 1.055 * a ** (1 / 2.4) - 0.055)
    return np.round(encoded * 255).astype(np.int16)


def assert_png_shows_exr(png_path, exr_image: np.ndarray, exposure: float = 0.0) -> None:
    """The PNG decodes to the EXR's pixels through the sRGB curve, within one level (the
    float32 EXR vs float64 here). Catches a PNG of another image, a linear (unencoded) PNG,
    a flipped or resized one, a wrong exposure."""
    from PIL import Image

    png = np.asarray(Image.open(png_path).convert("RGB"), np.int16)
    expected = srgb_8bit(np.asarray(exr_image)[..., :3] * 2.0**exposure)
    assert png.shape == expected.shape, (png.shape, expected.shape)
    assert np.abs(png - expected).max() <= 1
