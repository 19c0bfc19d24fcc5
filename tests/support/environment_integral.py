"""The environment's radiance integrated over the sphere by midpoint quadrature in
(cos theta about +Y, phi), and the z-score of a sampler's E[L / pdf] against it: shared by
the renderer's environment-sampling tests."""
from __future__ import annotations

import numpy as np


def sphere_integral(core, n_cos: int = 2000, n_phi: int = 256) -> np.ndarray:
    ct, phi = np.meshgrid(-1 + (np.arange(n_cos) + 0.5) * 2 / n_cos, np.arange(n_phi) * 2 * np.pi / n_phi,
                          indexing="ij")
    st = np.sqrt(1 - ct ** 2)
    grid = np.stack([st * np.sin(phi), ct, -st * np.cos(phi)], -1).reshape(-1, 3)
    return core.environment_eval(grid).mean(axis=0) * 4 * np.pi


def estimate_z(estimates: np.ndarray, integral: np.ndarray) -> np.ndarray:
    """Per channel: (mean of the estimates - integral) / the mean's standard error."""
    return (estimates.mean(axis=0) - integral) / (estimates.std(axis=0) / np.sqrt(len(estimates)))
