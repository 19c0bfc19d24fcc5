"""Smooth conductor (complex Fresnel mirror), optionally thin-film coated."""
from __future__ import annotations

import numpy as np

from bsdflab import _core
from bsdflab.bsdfs.base import BSDF
from bsdflab.bsdfs.interface_term import DEFAULT_EXT_IOR, ConductorParams


class Conductor(ConductorParams, BSDF):
    """Perfect specular reflection weighted by the unpolarised Fresnel reflectance of a
    complex index of refraction eta + i k, per wavelength.

    Give either ``material`` (a named metal, see ``bsdflab.optics.metals.METALS``) or
    ``eta`` and ``k`` (numbers or spectra). The lobe is a delta: ``eval`` and ``pdf``
    return 0; use ``sample``.

    Parameters
    ----------
    material : str, optional
        Named metal whose measured (eta, k) spectra ship with bsdflab. With neither
        ``material`` nor (eta, k), or ``material="none"``, a perfect mirror (R = 1).
    eta : float, dict or Spectrum > 0
        Real part of the index (absolute, i.e. relative to vacuum).
    k : float, dict or Spectrum >= 0
        Extinction coefficient.
    ext_ior : float > 0
        Index of the exterior medium. Default 1.000277 (air).
    two_sided : bool
        Reflect from both sides (default: the underside is black, as in Mitsuba).
    film : list of FilmLayer or dicts, optional
        A thin-film coating (top first), e.g. ``[{"material": 1.5, "thickness_nm": 400}]``
        (like the ``conductorThinFilm`` of Padrón-Griffe et al. 2023). Its thickness can vary
        per query (``thickness_nm=``).
    """

    type_name = "conductor"

    def __init__(self, material: str | None = None, eta=None, k=None,
                 ext_ior: float = DEFAULT_EXT_IOR, two_sided: bool = False, film=None):
        super().__init__()
        self._init_conductor(material, eta, k, ext_ior, two_sided, film)

    def _build(self, wavelengths: np.ndarray):
        return _core.SmoothInterface(wavelengths, self._conductor_term(wavelengths), self.two_sided)

    def _params(self):
        return self._conductor_params()
