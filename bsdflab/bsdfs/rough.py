"""Rough interfaces: GGX (Trowbridge-Reitz) microfacets with Smith shadowing and
visible-normal sampling (Walter et al. 2007; Heitz 2018), optionally thin-film coated --
the seed's `roughdielectricThinFilm` and a rough `conductorThinFilm`.

Single scattering only: light that would bounce between microfacets is lost, so the
white-furnace albedo falls below 1 as roughness grows (about 1-3 % at alpha 0.3, more at
grazing angles and high roughness). This is expected and documented, not a bug.
"""
from __future__ import annotations

import numpy as np

from .. import _core
from .._validate import real_scalar
from .base import BSDF
from .interface_term import (DEFAULT_EXT_IOR, DEFAULT_INT_IOR, ConductorParams, ext_ior_param,
                             film_to_list, int_ior_param, make_term, parse_film)


def _alpha(value) -> float:
    # Below ~1e-4 the GGX lobe is narrower than double precision resolves near the peak.
    return real_scalar("alpha", value, 1e-4, 4.0)


class RoughConductor(ConductorParams, BSDF):
    """Rough metal: GGX microfacets, each a Fresnel mirror of the complex index.

    Parameters
    ----------
    alpha : float in [1e-4, 4]
        GGX roughness (alpha = perceptual roughness squared). Default 0.1.
    material, eta, k, ext_ior, two_sided, film
        As for ``Conductor``.
    """

    type_name = "roughconductor"

    def __init__(self, alpha: float = 0.1, material: str | None = None, eta=None, k=None,
                 ext_ior: float = DEFAULT_EXT_IOR, two_sided: bool = False, film=None):
        super().__init__()
        self.alpha = _alpha(alpha)
        self._init_conductor(material, eta, k, ext_ior, two_sided, film)

    def _build(self, wavelengths: np.ndarray):
        return _core.RoughInterface(wavelengths, self._conductor_term(wavelengths), self.alpha,
                                    self.two_sided)

    def _params(self):
        return {"alpha": self.alpha, **self._conductor_params()}


class RoughDielectric(BSDF):
    """Rough dielectric interface: GGX reflection and refraction, both sides, TIR.

    Parameters
    ----------
    alpha : float in [1e-4, 4]
        GGX roughness. Default 0.1.
    int_ior, ext_ior, film
        As for ``Dielectric``.
    """

    type_name = "roughdielectric"

    def __init__(self, alpha: float = 0.1, int_ior: float = DEFAULT_INT_IOR,
                 ext_ior: float = DEFAULT_EXT_IOR, film=None):
        super().__init__()
        self.alpha = _alpha(alpha)
        self.ext_ior = ext_ior_param(ext_ior)
        self.int_ior = int_ior_param(int_ior, self.ext_ior)
        if self.int_ior == self.ext_ior:
            raise ValueError("int_ior must differ from ext_ior (an index-matched rough "
                             "interface has no well-defined half vector)")
        self.film = parse_film(film)

    def _build(self, wavelengths: np.ndarray):
        term = make_term(wavelengths, self.ext_ior, self.film, int_ior=self.int_ior)
        return _core.RoughInterface(wavelengths, term, self.alpha, False)

    def _params(self):
        p = {"alpha": self.alpha, "int_ior": self.int_ior, "ext_ior": self.ext_ior}
        if self.film:
            p["film"] = film_to_list(self.film)
        return p
