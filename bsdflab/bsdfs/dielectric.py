"""Smooth dielectric interface (Fresnel with energy-correct unpolarised averaging),
optionally thin-film coated."""
from __future__ import annotations

import numpy as np

from bsdflab import _core
from bsdflab.bsdfs.base import BSDF
from bsdflab.bsdfs.interface_term import (
    DEFAULT_EXT_IOR,
    DEFAULT_INT_IOR,
    ext_ior_param,
    film_to_list,
    int_ior_param,
    make_term,
    parse_film,
)


class Dielectric(BSDF):
    """Specular reflection and refraction between two non-absorbing media.

    The exterior (index ``ext_ior``) is above the surface (+z), the interior
    (``int_ior``) below. Reflection and transmission are chosen with the unpolarised
    Fresnel reflectance R = (|r_s|^2 + |r_p|^2) / 2 and T = 1 - R; light arriving from
    inside beyond the critical angle is totally reflected. With a ``film``, R and T are
    those of the coated interface per wavelength (the choice uses their channel means;
    weights carry each channel's value over that probability).

    Transmitted radiance is scaled by (n_i / n_t)^2, the solid-angle compression of
    radiance transport (radiance / n^2 is conserved): this is the weight a camera path
    carries. Both lobes are delta lobes: ``eval`` and ``pdf`` return 0; use ``sample``.

    Parameters
    ----------
    int_ior : float in [1e-3, 1e3]
        Index of refraction of the interior. Default 1.5046 (BK7 at 589 nm, Mitsuba's
        default). int_ior / ext_ior must lie in [0.01, 100] (docs/limits.md).
    ext_ior : float in [1e-3, 1e3]
        Index of refraction of the exterior. Default 1.000277 (air).
    film : list of FilmLayer or dicts, optional
        A thin-film coating on the exterior side (top first); thickness variable per query.
    """

    type_name = "dielectric"

    def __init__(self, int_ior: float = DEFAULT_INT_IOR, ext_ior: float = DEFAULT_EXT_IOR, film=None):
        super().__init__()
        self.ext_ior = ext_ior_param(ext_ior)
        self.int_ior = int_ior_param(int_ior, self.ext_ior)
        self.film = parse_film(film)

    def _build(self, wavelengths: np.ndarray):
        term = make_term(wavelengths, self.ext_ior, self.film, int_ior=self.int_ior)
        return _core.SmoothInterface(wavelengths, term, False)

    def _params(self):
        p = {"int_ior": self.int_ior, "ext_ior": self.ext_ior}
        if self.film:
            p["film"] = film_to_list(self.film)
        return p
