"""Lambertian reflector: f = reflectance / pi."""
from __future__ import annotations

import numpy as np

from bsdflab import _core
from bsdflab.bsdfs.base import BSDF
from bsdflab.spectra import Spectrum
from bsdflab.util import args as check


class Diffuse(BSDF):
    """Ideal diffuse reflection.

    Parameters
    ----------
    reflectance : float, RGB triple, dict or Spectrum, in [0, 1]
        Albedo (hemispherical reflectance). An RGB triple is linear sRGB. Default 0.5.
    two_sided : bool
        If True, light arriving from below (z < 0) is reflected back below as well;
        otherwise (Mitsuba's default) the underside is black.
    """

    type_name = "diffuse"

    def __init__(self, reflectance=0.5, two_sided: bool = False):
        super().__init__()
        self.reflectance = Spectrum.coerce(reflectance, "reflectance", 0.0, 1.0)
        self.two_sided = check.flag("two_sided", two_sided)

    def _build(self, wavelengths: np.ndarray):
        return _core.Diffuse(wavelengths, self.reflectance.at(wavelengths), self.two_sided)

    def render_core(self):
        # eval is linear in the reflectance, so a 3-channel Diffuse with the projected
        # reflectance gives exactly the RGB the spectral one does.
        # Its channels are R, G and B: labelled with the sRGB primaries' wavelengths (the
        # labels name the channels; a Diffuse never reads them).
        from bsdflab.spectra import DEFAULT_WAVELENGTHS, THREE_WAVELENGTHS_NM, srgb_weights

        rgb = srgb_weights(DEFAULT_WAVELENGTHS) @ self.reflectance.at(DEFAULT_WAVELENGTHS)
        return _core.Diffuse(np.array(THREE_WAVELENGTHS_NM), rgb, self.two_sided), None

    def render_lift(self):
        # The core answers rgb * c (c = cos / pi, or 1 for a sample weight) with rgb = W R,
        # so R rgb^T / |rgb|^2 returns R * c: the reflectance's own spectrum, also when it is
        # tabulated (the generic RGB lift would give U W R, a different spectrum).
        from bsdflab.spectra import DEFAULT_WAVELENGTHS, srgb_weights

        R = self.reflectance.at(DEFAULT_WAVELENGTHS)
        rgb = srgb_weights(DEFAULT_WAVELENGTHS) @ R
        norm = float(rgb @ rgb)
        return np.outer(R, rgb / norm) if norm > 0 else np.zeros((len(R), 3))

    def _params(self):
        return {"reflectance": self.reflectance.to_dict(), "two_sided": self.two_sided}
