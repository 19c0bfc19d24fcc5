"""Smooth dielectric interface (the seed's appendix A.3, with energy-correct Fresnel)."""
from __future__ import annotations

import numpy as np

from .. import _core
from .._validate import real_scalar
from .base import BSDF


class Dielectric(BSDF):
    """Specular reflection and refraction between two non-absorbing media.

    The exterior (index ``ext_ior``) is above the surface (+z), the interior
    (``int_ior``) below. Reflection and transmission are chosen with the unpolarised
    Fresnel reflectance R = (|r_s|^2 + |r_p|^2) / 2 and T = 1 - R; light arriving from
    inside beyond the critical angle is totally reflected.

    Transmitted radiance is scaled by (n_i / n_t)^2, the solid-angle compression of
    radiance transport (radiance / n^2 is conserved): this is the weight a camera path
    carries. Both lobes are delta lobes: ``eval`` and ``pdf`` return 0; use ``sample``.

    Parameters
    ----------
    int_ior : float > 0
        Index of refraction of the interior. Default 1.5046 (BK7 at 589 nm, Mitsuba's default).
    ext_ior : float > 0
        Index of refraction of the exterior. Default 1.000277 (air).
    """

    type_name = "dielectric"

    def __init__(self, int_ior: float = 1.5046, ext_ior: float = 1.000277):
        super().__init__()
        self.int_ior = real_scalar("int_ior", int_ior, 0.0, lo_open=True)
        self.ext_ior = real_scalar("ext_ior", ext_ior, 0.0, lo_open=True)

    def _build(self, wavelengths: np.ndarray):
        return _core.Dielectric(wavelengths, self.int_ior, self.ext_ior)

    def _params(self):
        return {"int_ior": self.int_ior, "ext_ior": self.ext_ior}
