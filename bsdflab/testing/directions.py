"""Direction helpers shared by the testing kit: building and drawing unit vectors.

All directions use bsdflab's local frame: +z is the surface normal, z < 0 is the
transmission side.
"""
from __future__ import annotations

import numpy as np

from bsdflab.util import args as check

_HEMISPHERES = (None, "upper", "lower")


def spherical_directions(theta, phi) -> np.ndarray:
    """Unit vectors from polar angle ``theta`` and azimuth ``phi`` (radians).

    Parameters
    ----------
    theta : float or array_like
        Angle from +z in [0, pi]; theta > pi/2 points below the surface.
    phi : float or array_like
        Azimuth measured from +x towards +y. Broadcast against ``theta``.

    Returns
    -------
    numpy.ndarray
        Shape ``broadcast(theta, phi).shape + (3,)``; a scalar pair gives shape (3,),
        ready to use as a single ``wi``.

    Examples
    --------
    >>> spherical_directions(0.0, 0.0).tolist()
    [0.0, 0.0, 1.0]
    """
    t = check.real_array("theta", theta, 0.0, np.pi)
    p = check.real_array("phi", phi)
    t, p = np.broadcast_arrays(t, p)
    sin_t = np.sin(t)
    return np.stack([sin_t * np.cos(p), sin_t * np.sin(p), np.cos(t)], axis=-1)


def random_unit_vectors(n: int, seed: int = 0, hemisphere: str | None = None) -> np.ndarray:
    """``n`` directions uniformly distributed over the sphere or one hemisphere.

    Parameters
    ----------
    n : int >= 1
        Number of directions.
    seed : int >= 0
        Seed of the numpy PCG64 generator, so the result is repeatable.
    hemisphere : {None, 'upper', 'lower'}
        None for the whole sphere; 'upper' for z >= 0; 'lower' for z <= 0.

    Returns
    -------
    numpy.ndarray
        Shape (n, 3), unit length.
    """
    n = positive_int("n", n)
    if hemisphere not in _HEMISPHERES:
        raise ValueError(f"hemisphere must be None, 'upper' or 'lower', got {hemisphere!r}")
    rng = np.random.default_rng(check.seed(seed))
    u = rng.random((n, 2))
    # z uniform in [-1, 1] (or a half of it) gives uniform solid angle (Archimedes).
    if hemisphere is None:
        z = 1.0 - 2.0 * u[:, 0]
    elif hemisphere == "upper":
        z = u[:, 0]
    else:
        z = -u[:, 0]
    return directions_from_cos_phi(z, 2.0 * np.pi * u[:, 1] - np.pi)


def directions_from_cos_phi(cos_theta: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """Unit vectors from cos(theta) in [-1, 1] and phi (no validation; internal use)."""
    cos_theta, phi = np.broadcast_arrays(cos_theta, phi)
    sin_t = np.sqrt(np.clip(1.0 - cos_theta * cos_theta, 0.0, None))
    return np.stack([sin_t * np.cos(phi), sin_t * np.sin(phi), cos_theta], axis=-1)


def single_direction(name: str, value) -> np.ndarray:
    """One unit vector of shape (3,), with bsdflab's usual checks."""
    d = check.directions(name, value)
    if len(d) != 1:
        raise ValueError(f"{name} must be a single direction of shape (3,), got {len(d)} rows")
    return d[0]


def positive_int(name: str, value) -> int:
    """An integer >= 1 (bool rejected)."""
    return check.integer(name, value, 1)
