"""The sRGB transfer curve (IEC 61966-2-1), linear -> encoded.

colour-science has it (``colour.cctf_encoding(x, function="sRGB")``) and is the reference
it is tested against, bit for bit (tests/optics/test_srgb_curve.py). It is written here
because ``import colour`` imports colour's plotting, matplotlib, scipy and pandas: about
2.4 CPU-s, which every ``bsdflab render`` that writes a PNG paid for this one curve.
"""
from __future__ import annotations

import numpy as np

LINEAR_KNEE = 0.0031308   # below it the curve is linear, with slope 12.92


def srgb_encode(linear) -> np.ndarray:
    """Encoded sRGB of linear values (float64, computed as colour-science does)."""
    x = np.asarray(linear, dtype=np.float64)
    return np.where(x <= LINEAR_KNEE, x * 12.92, 1.055 * np.sign(x) * np.abs(x) ** (1 / 2.4) - 0.055)
