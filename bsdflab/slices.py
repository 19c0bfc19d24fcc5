"""A BSDF's values as data for viewers: given direction pairs or angles, the plane of
incidence, and the hemisphere of outgoing directions (what the lobe explorer plots).

Values follow the BSDF interface: f(wi, wo) |cos theta_o|, linear sRGB (D65) or one column
per wavelength. Stochastic (layered) models also return the standard error of each value,
from ``samples`` walks seeded by ``seed``; the same call gives the same numbers.
Geometry: wi lies in the x-z plane on the -x side (light arrives from -x), so the mirror
direction is at signed angle +theta_i in the plane of incidence and at x = +sin theta_i on
the hemisphere grid.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bsdflab.bsdfs.base import BSDF
from bsdflab.lobes import Lobe
from bsdflab.tables.channels import LUMINANCE_RGB
from bsdflab.util import args as check
from bsdflab.util.deprecation import renamed_keywords


@dataclass(frozen=True)
class Values:
    values: np.ndarray            # (N, C) f |cos theta_o|
    stderr: np.ndarray | None     # (N, C) standard errors; None for deterministic models


def is_stochastic(bsdf: BSDF) -> bool:
    return hasattr(bsdf, "eval_with_error")


@renamed_keywords(thickness="thickness_nm")
def evaluate(bsdf: BSDF, wi, wo, wavelengths=None, samples: int | None = None,
             seed: int | None = None, thickness_nm=None) -> Values:
    """``bsdf.eval`` for every (wi, wo) pair, with standard errors for stochastic models.
    ``samples`` and ``seed`` replace a stochastic model's own (ignored otherwise);
    ``thickness_nm`` (one or one per pair) replaces a thin-film coating's total thickness."""
    if is_stochastic(bsdf):
        value, err = bsdf.eval_with_error(wi, wo, wavelengths=wavelengths, samples=samples, seed=seed,
                                          thickness_nm=thickness_nm)
        return Values(value, err)
    return Values(bsdf.eval(wi, wo, wavelengths=wavelengths, thickness_nm=thickness_nm), None)


def directions_from_angles(theta_i_deg, theta_o_deg, phi_deg) -> tuple[np.ndarray, np.ndarray]:
    """(wi, wo) from incidence and outgoing polar angles and the azimuth phi_o - phi_i, in
    degrees, broadcast against each other: wi at azimuth 0, so the mirror direction is at
    phi = 180. theta_o > 90 points below the surface (transmission)."""
    ti = check.real_array("theta_i", theta_i_deg, 0.0, 90.0)
    to = check.real_array("theta_o", theta_o_deg, 0.0, 180.0)
    ph = check.real_array("phi", phi_deg, -360.0, 360.0)
    ti, to, ph = (np.radians(np.ravel(a)) for a in np.broadcast_arrays(ti, to, ph))
    # (bsdflab.testing.directions.spherical_directions, without importing the testing kit)
    wi = np.stack([np.sin(ti), np.zeros_like(ti), np.cos(ti)], axis=1)
    wo = np.stack([np.sin(to) * np.cos(ph), np.sin(to) * np.sin(ph), np.cos(to)], axis=1)
    return wi, wo


def incident(theta_i_deg: float) -> np.ndarray:
    """wi at ``theta_i`` degrees from the normal, arriving from the -x side."""
    t = np.radians(check.real_scalar("theta_i", theta_i_deg, 0.0, 90.0, hi_open=True))
    return np.array([-np.sin(t), 0.0, np.cos(t)])


def plane_of_incidence(bsdf: BSDF, theta_i_deg: float, points: int = 181, samples: int | None = None,
                       seed: int | None = None) -> tuple[np.ndarray, Values]:
    """(signed outgoing angles in degrees, values) along the plane of incidence: -90..90
    for a reflecting model, -180..180 when it transmits (|angle| > 90 is below)."""
    points = check_count("points", points, 3)
    limit = 180.0 if bsdf.lobes & Lobe.TRANSMISSION else 90.0
    angles = np.linspace(-limit, limit, points)
    t = np.radians(angles)
    wo = np.stack([np.sin(t), np.zeros_like(t), np.cos(t)], axis=1)
    return angles, evaluate(bsdf, incident(theta_i_deg), wo, samples=samples, seed=seed)


def hemisphere(bsdf: BSDF, theta_i_deg: float, resolution: int = 48, samples: int | None = None,
               seed: int | None = None) -> tuple[np.ndarray, np.ndarray, Values]:
    """(grid coordinates (R,), inside mask (R, R), values of the inside cells (M, 3)): the
    upper hemisphere seen orthographically from above, x to the right, y up."""
    resolution = check_count("resolution", resolution, 3)
    x = np.linspace(-1.0, 1.0, resolution)
    X, Y = np.meshgrid(x, x)
    inside = X**2 + Y**2 < 1.0
    wo = np.stack([X[inside], Y[inside], np.sqrt(1.0 - X[inside]**2 - Y[inside]**2)], axis=1)
    return x, inside, evaluate(bsdf, incident(theta_i_deg), wo, samples=samples, seed=seed)


def luminance(rgb: np.ndarray) -> np.ndarray:
    """Rec. 709 luminance of linear-sRGB rows (N, 3) -> (N,)."""
    return np.asarray(rgb) @ LUMINANCE_RGB


def check_count(name: str, value, lo: int) -> int:
    return check.integer(name, value, lo, 1 << 16)
