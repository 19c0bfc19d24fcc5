"""A denoised preview of a render through Intel Open Image Denoise (the PyPI binding
``pyoidn``), guided by the first-hit albedo and normal images. The preview is written
*beside* the unbiased image, never instead of it: nothing here touches ``result.mean``."""
from __future__ import annotations

import numpy as np

from bsdflab.util.extras import require


def denoise(result) -> np.ndarray:
    """The denoised (H, W, 3) float32 image of ``result`` (a RenderResult rendered with
    ``aovs=True``)."""
    if result.aovs is None:
        raise ValueError("denoise needs a render with aovs=True (albedo and normal images)")
    pyoidn = require("pyoidn", "denoise")
    color = np.ascontiguousarray(np.maximum(result.mean, 0.0), dtype=np.float32)
    albedo = np.ascontiguousarray(np.clip(result.aovs["albedo"], 0.0, 1.0), dtype=np.float32)
    normal = np.ascontiguousarray(result.aovs["normal"], dtype=np.float32)
    return np.asarray(pyoidn.denoise(color, albedo, normal, hdr=True))
