"""Environment images for the renderer: the sky gradient and lat-long EXR maps.

Both become a lat-long image in Mitsuba's mapping (see ``Environment``): row j covers
polar angle theta in [j, j+1) pi / H measured from +Y, column i covers
phi = atan2(x, -z) in [i, i+1) 2 pi / W.
"""
from __future__ import annotations

import numpy as np

from bsdflab.render.image_io import read_exr
from bsdflab.render.scene import Environment

SKY_HEIGHT = 128


def sky_image(env: Environment, height: int = SKY_HEIGHT) -> np.ndarray:
    """The sky gradient as an (H, 2H, 3) lat-long image: horizon colour at the horizon
    blending to the zenith colour as sqrt(sin(elevation)) (a bright horizon band, as in a
    clear sky), and the ground colour below the horizon. Constant along phi."""
    theta = (np.arange(height) + 0.5) * np.pi / height
    elevation = 0.5 * np.pi - theta
    t = np.sqrt(np.clip(np.sin(elevation), 0.0, 1.0))[:, None]
    above = (1 - t) * np.asarray(env.horizon) + t * np.asarray(env.zenith)
    rows = np.where((elevation > 0)[:, None], above, np.asarray(env.ground))
    return np.repeat(rows[:, None, :], 2 * height, axis=1).astype(np.float32)


def environment_image(env: Environment, base_dir: str | None = None) -> np.ndarray | None:
    """The lat-long image of a sky or envmap environment (before ``scale``); None for
    "none" and "constant"."""
    if env.type == "sky":
        return sky_image(env)
    if env.type == "envmap":
        import os

        path = env.path if base_dir is None or os.path.isabs(env.path) else os.path.join(base_dir, env.path)
        image = read_exr(path)
        if image.shape[0] < 2 or image.shape[1] < 2:
            raise ValueError(f"environment map {path} is too small ({image.shape[1]}x{image.shape[0]})")
        if not np.all(np.isfinite(image)) or np.any(image < 0):
            raise ValueError(f"environment map {path} has negative or non-finite pixels")
        return image
    return None
