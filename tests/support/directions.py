"""Direction helpers with fixed conventions (+z is the normal)."""
from __future__ import annotations

import numpy as np


def unit(v):
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def directions_at(cos_theta, phi=0.3):
    """A direction with the given cos(theta) (sign = hemisphere) and azimuth."""
    s = np.sqrt(max(0.0, 1 - cos_theta**2))
    return np.array([s * np.cos(phi), s * np.sin(phi), cos_theta])


def random_directions(rng, n, hemisphere=None):
    v = unit(rng.normal(size=(n, 3)))
    if hemisphere == "upper":
        v[:, 2] = np.abs(v[:, 2])
    elif hemisphere == "lower":
        v[:, 2] = -np.abs(v[:, 2])
    return v
