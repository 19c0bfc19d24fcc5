"""Smooth conductor (the seed's appendix A.2): a Fresnel-weighted mirror."""
from __future__ import annotations

import numpy as np

from .. import _core
from .._validate import real_scalar
from ..optics.metals import metal_ior
from ..spectra import Spectrum
from .base import BSDF


class Conductor(BSDF):
    """Perfect specular reflection weighted by the unpolarised Fresnel reflectance of a
    complex index of refraction eta + i k, per wavelength.

    Give either ``material`` (a named metal, see ``bsdflab.optics.metals.METALS``) or
    ``eta`` and ``k`` (numbers or spectra). The lobe is a delta: ``eval`` and ``pdf``
    return 0; use ``sample``.

    Parameters
    ----------
    material : str, optional
        Named metal whose measured (eta, k) spectra are shipped with bsdflab.
    eta : float, dict or Spectrum > 0
        Real part of the index (relative to vacuum). With neither ``material`` nor
        (eta, k) given, or ``material="none"``, the conductor is a perfect mirror (R = 1).
    k : float, dict or Spectrum >= 0
        Extinction coefficient.
    ext_ior : float > 0
        Index of the exterior medium. Default 1.000277 (air).
    two_sided : bool
        Reflect from both sides (default: the underside is black, as in Mitsuba).
    """

    type_name = "conductor"

    def __init__(self, material: str | None = None, eta=None, k=None,
                 ext_ior: float = 1.000277, two_sided: bool = False):
        super().__init__()
        if material is not None and (eta is not None or k is not None):
            raise ValueError("give either material or (eta, k), not both")
        if material is None and eta is None and k is None:
            material = "none"
        self.material = material
        if material == "none":
            # A perfect mirror, as Mitsuba's default: eta = 0, k = 1 gives R = 1 everywhere.
            self.eta, self.k = Spectrum.constant(0.0), Spectrum.constant(1.0)
        else:
            if material is not None:
                eta, k = metal_ior(material)
            self.eta = Spectrum.coerce(eta if eta is not None else 1.0, "eta", 0.0, lo_open=True)
            self.k = Spectrum.coerce(k if k is not None else 0.0, "k", 0.0)
        self.ext_ior = real_scalar("ext_ior", ext_ior, 0.0, lo_open=True)
        self.two_sided = bool(two_sided)

    def _build(self, wavelengths: np.ndarray):
        return _core.Conductor(wavelengths, self.eta.at(wavelengths), self.k.at(wavelengths),
                               self.ext_ior, self.two_sided)

    def _params(self):
        if self.material is not None:
            p = {"material": self.material} if self.material != "none" else {}
        else:
            p = {"eta": self.eta.to_dict(), "k": self.k.to_dict()}
        return {**p, "ext_ior": self.ext_ior, "two_sided": self.two_sided}
