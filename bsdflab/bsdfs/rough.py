"""Rough interfaces: GGX (Trowbridge-Reitz) or Beckmann microfacets with separable Smith
shadowing and visible-normal sampling (Walter et al. 2007; Heitz & d'Eon 2014; Heitz
2018), optionally thin-film coated -- like the `roughdielectricThinFilm` and `conductorThinFilm`
plugins of Padrón-Griffe et al. 2023, and a rough conductor with a film.

By default single scattering only (Mitsuba's model): light that would bounce between
microfacets is lost, so the white-furnace albedo falls below 1 as roughness grows --
far more than a few percent. Measured (GGX, alpha 0.3; docs/rough_interfaces.md): a
white (F = 1) conductor keeps 0.878 / 0.819 / 0.822 at 0 / 60 / 80 deg (GGX's long tail
tilts 8 % of the facets past 45 deg); glass (eta 1.5) keeps R + T = 0.989 / 0.947 at
0 / 60 deg from outside but only 0.900 / 0.871 / 0.780 at 0 / 30 / 60 deg from inside
(total internal reflection on steep facets). Beckmann loses less (1.000 / 0.924 white
conductor at 0 / 60 deg). ``multiscatter=True`` adds Kulla & Conty's (2017) energy
compensation, so that a lossless interface conserves energy from both sides.
"""
from __future__ import annotations

import numpy as np

from bsdflab import _core
from bsdflab.bsdfs.base import BSDF
from bsdflab.bsdfs.interface_term import (
    DEFAULT_EXT_IOR,
    DEFAULT_INT_IOR,
    ConductorParams,
    ext_ior_param,
    film_to_list,
    int_ior_param,
    make_term,
    parse_film,
)
from bsdflab.util.args import flag, real_scalar

DISTRIBUTIONS = ("ggx", "beckmann")


def _alpha(value) -> float:
    # Below ~1e-4 the GGX lobe is narrower than double precision resolves near the peak.
    return real_scalar("alpha", value, 1e-4, 4.0)


def _distribution(value) -> str:
    if not isinstance(value, str) or value.lower() not in DISTRIBUTIONS:
        raise ValueError(f"distribution must be one of {', '.join(DISTRIBUTIONS)}, got {value!r}")
    return value.lower()


class _Microfacets:
    """The microfacet parameters both rough interfaces share, and their dict form (the
    defaults, GGX and single scattering, are left out so that older dicts keep meaning)."""

    alpha: float
    distribution: str
    multiscatter: bool

    def _init_microfacets(self, alpha, distribution, multiscatter) -> None:
        self.alpha = _alpha(alpha)
        self.distribution = _distribution(distribution)
        self.multiscatter = flag("multiscatter", multiscatter)

    def _interface(self, wavelengths, term, two_sided: bool):
        return _core.RoughInterface(wavelengths, term, self.alpha, two_sided,
                                    self.distribution, self.multiscatter)

    def _microfacet_params(self) -> dict:
        p = {"alpha": self.alpha}
        if self.distribution != "ggx":
            p["distribution"] = self.distribution
        if self.multiscatter:
            p["multiscatter"] = True
        return p


_PARAMS_DOC = """alpha : float in [1e-4, 4]
        Roughness (GGX: alpha = perceptual roughness squared; Beckmann: RMS slope / sqrt 2).
        Default 0.1.
    distribution : 'ggx' (default) or 'beckmann'
        The microfacet normal distribution.
    multiscatter : bool, default False
        Add the Kulla-Conty multiple-scattering energy compensation (energy tables built
        when the model is first used at a set of wavelengths; docs/rough_interfaces.md)."""


class RoughConductor(_Microfacets, ConductorParams, BSDF):
    """Rough metal: microfacets, each a Fresnel mirror of the complex index.

    Parameters
    ----------
    {params}
    material, eta, k, ext_ior, two_sided, film
        As for ``Conductor``. With a film the compensation's tint follows the film's
        average reflectance (at the query's thickness).
    """

    type_name = "roughconductor"

    def __init__(self, alpha: float = 0.1, material: str | None = None, eta=None, k=None,
                 ext_ior: float = DEFAULT_EXT_IOR, two_sided: bool = False, film=None,
                 distribution: str = "ggx", multiscatter: bool = False):
        super().__init__()
        self._init_microfacets(alpha, distribution, multiscatter)
        self._init_conductor(material, eta, k, ext_ior, two_sided, film)

    def _build(self, wavelengths: np.ndarray):
        return self._interface(wavelengths, self._conductor_term(wavelengths), self.two_sided)

    def _params(self):
        return {**self._microfacet_params(), **self._conductor_params()}


class RoughDielectric(_Microfacets, BSDF):
    """Rough dielectric interface: microfacet reflection and refraction, both sides, TIR.

    Parameters
    ----------
    {params}
    int_ior, ext_ior, film
        As for ``Dielectric``. Indices within a relative 1e-6 of each other (and no film)
        make no interface: light passes straight through (a smooth index-matched one).
    """

    type_name = "roughdielectric"

    def __init__(self, alpha: float = 0.1, int_ior: float = DEFAULT_INT_IOR,
                 ext_ior: float = DEFAULT_EXT_IOR, film=None, distribution: str = "ggx",
                 multiscatter: bool = False):
        super().__init__()
        self._init_microfacets(alpha, distribution, multiscatter)
        self.ext_ior = ext_ior_param(ext_ior)
        self.int_ior = int_ior_param(int_ior, self.ext_ior)
        if self.int_ior == self.ext_ior:
            raise ValueError("int_ior must differ from ext_ior (an index-matched rough "
                             "interface has no well-defined half vector)")
        self.film = parse_film(film)

    def _build(self, wavelengths: np.ndarray):
        term = make_term(wavelengths, self.ext_ior, self.film, int_ior=self.int_ior)
        return self._interface(wavelengths, term, False)

    def _params(self):
        p = {**self._microfacet_params(), "int_ior": self.int_ior, "ext_ior": self.ext_ior}
        if self.film:
            p["film"] = film_to_list(self.film)
        return p


for _cls in (RoughConductor, RoughDielectric):
    _cls.__doc__ = _cls.__doc__.replace("{params}", _PARAMS_DOC)
