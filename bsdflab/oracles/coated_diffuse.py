r"""Reference model ("oracle") of a coated, absorbing slab over a Lambertian base.

What it models
--------------
From top to bottom: an exterior of real index n_ext; a smooth interface, optionally coated
on its exterior side with a coherent thin-film stack; a non-scattering slab of real index
n_slab, thickness d (µm) and absorption coefficient sigma_a(lambda) (1/µm); a Lambertian
base of albedo rho(lambda). It is a deterministic reference for validating the
Position-Free Monte Carlo layered BSDF: exact up to quadrature and interpolation
precision (~1e-13), vectorised, and independent of bsdflab's C++ optics (every Fresnel
and thin-film power comes from the ``tmm`` package). It is not a production BSDF: no
sampling, no pdf, no delta lobe in ``eval``.

Formula (radiance transport; wi, wo above the surface, cosines c_i, c_o)
------------------------------------------------------------------------
    f(wi, wo) = T_ext(c_i) A(c_i') rho/pi A(c_o') T_slab(c_o') / (eta^2 (1 - rho gamma)),

    eta = n_slab / n_ext,   A(c') = exp(-sigma_a d / c'),   c' the refracted cosines,
    gamma = int_{hemisphere} (cos u / pi) exp(-2 sigma_a d / cos u) R_slab(u) d omega_u,

and ``eval`` returns f c_o. T_ext is the coated interface's transmittance for light
arriving from outside at c_i; T_slab the transmittance for light arriving from the slab
at c_o' (the exit path of wo). R_slab is the reflectance seen from the slab (the reversed
stack; 1 beyond the critical angle for a bare interface or a lossless film, less under an
absorbing film). The delta specular reflection R_ext(c_i) is left out of f and returned
by ``specular_reflectance``.

Derivation sketch. Planar layers are position-free: flux per unit area is conserved along
a parallel beam, so irradiance E = L_i c_i d omega_i reaches the base as
E_0 = T_ext A(c_i') E. The base reflects rho E_b as radiance rho E_b / pi; the fraction of
that emission which returns to the base after one reflection at the top is gamma, so
E_b = E_0 + rho gamma E_b, i.e. E_b = E_0 / (1 - rho gamma) (all orders summed). The base
radiance is attenuated by A(c_o') and crosses the top; radiance / n^2 is invariant across
the interface, so the exterior radiance is T_slab L / eta^2. Dividing by E gives f.

Transmittance from the two sides. For each polarisation the power transmittance of a
reciprocal stack between lossless half-spaces is the same in both directions, absorbing
layers included (R is not). tmm confirms T_ext(c_e) = T_slab(c_s) to ~1e-16 for
absorbing films (tests/test_oracle_coated_diffuse.py checks it), so f is reciprocal;
the model still uses T_slab, the physically right one, for the way out.

Checks of the 1/eta^2. With sigma_a = 0, rho = 1 and a lossless top, gamma is the
internal diffuse reflectance F_int and the étendue identity 1 - F_ext = eta^2 (1 - F_int)
gives int f c_o d omega_o = T_ext(c_i) = 1 - R_ext(c_i): the albedo plus the specular
part is exactly 1 (tested). With n_slab = n_ext and no film, f = rho / pi.

Validity. Smooth, planar interfaces; incoherent addition inside the slab (d much longer
than the coherence length, so no interference between bounces in the slab); films
coherent; real exterior and slab indices; unpolarised light with polarisation ignored
between bounces (each crossing uses the unpolarised average (X_s + X_p) / 2, as the
layered BSDF does); the base depolarises. Numerical: integrals by adaptive Gauss-Legendre
(converged to 1e-14), coated-interface powers as Chebyshev interpolants of tmm.coh_tmm
(1e-13); thick absorbing films or micron-thick coatings need more points and are slower.

Units: wavelengths and film thicknesses in nm, slab thickness in µm, sigma_a in 1/µm.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from bsdflab.bsdfs.interface_term import film_to_list, parse_film
from bsdflab.oracles._hemisphere import attenuation, escape, internal_return
from bsdflab.oracles._interface import InterfaceAtWavelength
from bsdflab.spectra import DEFAULT_WAVELENGTHS, Spectrum, srgb_weights
from bsdflab.util import args as check

_CACHE_LIMIT = 512  # wavelengths remembered per oracle


class CoatedDiffuseOracle:
    """Exact non-delta BSDF of a (coated) dielectric over an absorbing slab over a
    Lambertian base; see the module docstring for the formula.

    Parameters
    ----------
    int_ior : float
        Slab index n_slab, > 0.
    ext_ior : float
        Exterior index n_ext, > 0.
    film : list of FilmLayer or dicts {"material", "thickness_nm"}, optional
        Coherent coating on the exterior side of the top, exterior side first (see
        ``bsdflab.bsdfs.interface_term.parse_film``); thicknesses in nm.
    thickness_um : float
        Slab thickness d in µm, >= 0.
    sigma_a : number, RGB triple, dict or Spectrum
        Absorption coefficient in 1/µm, >= 0.
    base_reflectance : number, RGB triple, dict or Spectrum
        Lambertian albedo rho of the base, in [0, 1].
    """

    type_name = "coated_diffuse_oracle"

    def __init__(self, int_ior: float = 1.5, ext_ior: float = 1.0, film=None,
                 thickness_um: float = 0.0, sigma_a=0.0, base_reflectance=0.5):
        self.int_ior = check.real_scalar("int_ior", int_ior, 0.0, lo_open=True)
        self.ext_ior = check.real_scalar("ext_ior", ext_ior, 0.0, lo_open=True)
        self.film = parse_film(film)
        self.thickness_um = check.real_scalar("thickness_um", thickness_um, 0.0)
        self.sigma_a = Spectrum.coerce(sigma_a, "sigma_a", 0.0)
        self.base_reflectance = Spectrum.coerce(base_reflectance, "base_reflectance", 0.0, 1.0)
        self._optics: dict[float, InterfaceAtWavelength] = {}
        self._terms: dict[float, tuple[float, float]] = {}

    @property
    def eta(self) -> float:
        """n_slab / n_ext."""
        return self.int_ior / self.ext_ior

    # -- the interface ------------------------------------------------------------------
    def eval(self, wi, wo, wavelengths=None) -> np.ndarray:
        """f(wi, wo) |cos theta_o| without the delta specular lobe, shape (N, C).

        Parameters
        ----------
        wi, wo : array_like, (N, 3) or (3,)
            Unit directions, both pointing away from the surface (+z normal).
        wavelengths : array_like or None
            Vacuum wavelengths in nm (one column each), or None for linear sRGB through
            the default 5 nm grid (slow with a film: one tmm fit per wavelength).
        """
        a, b = check.direction_pair(wi, wo)
        wl, to_rgb = self._channels(wavelengths)
        c_i, c_o = a[:, 2], b[:, 2]
        active = (c_i > 0) & (c_o > 0)
        out = np.zeros((len(a), len(wl)))
        for j, lam in enumerate(wl):
            if not np.any(active):
                break
            rho, tau, gamma, _ = self._spectral(lam)
            at = self._at(lam)
            inc, exi = at.from_exterior(c_i[active]), at.from_exterior(c_o[active])
            f = (self._through(inc, "T_ext", tau) * self._through(exi, "T_slab", tau)
                 * rho / (np.pi * self.eta ** 2 * (1.0 - rho * gamma)))
            out[active, j] = f * c_o[active]
        return out @ to_rgb.T if to_rgb is not None else out

    def albedo(self, wi, wavelengths=None) -> np.ndarray:
        """Directional albedo of the non-delta part, int f cos theta_o d omega_o, by
        quadrature; shape (N, C). Add ``specular_reflectance`` for the total."""
        w = check.directions("wi", wi)
        wl, to_rgb = self._channels(wavelengths)
        c_i = w[:, 2]
        active = c_i > 0
        out = np.zeros((len(w), len(wl)))
        for j, lam in enumerate(wl):
            if not np.any(active):
                break
            rho, tau, gamma, leaving = self._spectral(lam)
            inc = self._at(lam).from_exterior(c_i[active])
            out[active, j] = (self._through(inc, "T_ext", tau) * rho * leaving
                              / (self.eta ** 2 * (1.0 - rho * gamma)))
        return out @ to_rgb.T if to_rgb is not None else out

    def specular_reflectance(self, wi, wavelengths=None) -> np.ndarray:
        """Weight of the delta reflection, R_ext(theta_i) of the coated top; shape (N, C)."""
        w = check.directions("wi", wi)
        wl, to_rgb = self._channels(wavelengths)
        active = w[:, 2] > 0
        out = np.zeros((len(w), len(wl)))
        for j, lam in enumerate(wl):
            if np.any(active):
                out[active, j] = self._at(lam).from_exterior(w[active, 2])["R_ext"]
        return out @ to_rgb.T if to_rgb is not None else out

    def internal_return(self, wavelengths) -> np.ndarray:
        """gamma per wavelength (L,): the base emission's fraction returned to the base."""
        wl, _ = self._channels(wavelengths)
        return np.array([self._spectral(lam)[2] for lam in wl])

    # -- serialisation --------------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-compatible parameters; ``CoatedDiffuseOracle.from_dict`` inverts it."""
        return {"type": self.type_name, "int_ior": self.int_ior, "ext_ior": self.ext_ior,
                "film": film_to_list(self.film), "thickness_um": self.thickness_um,
                "sigma_a": self.sigma_a.to_dict(),
                "base_reflectance": self.base_reflectance.to_dict()}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> CoatedDiffuseOracle:
        params = {k: v for k, v in d.items() if k != "type"}
        if d.get("type", cls.type_name) != cls.type_name:
            raise ValueError(f"expected type {cls.type_name!r}, got {d.get('type')!r}")
        return cls(**params)

    def __repr__(self) -> str:
        params = ", ".join(f"{k}={v!r}" for k, v in self.to_dict().items() if k != "type")
        return f"CoatedDiffuseOracle({params})"

    # -- internals ------------------------------------------------------------------------
    @staticmethod
    def _through(side: dict[str, np.ndarray], key: str, tau: float) -> np.ndarray:
        """Transmittance times the slab's attenuation along the refracted ray (0 where
        nothing transmits, so no exp(-tau / 0))."""
        c_s = side["c_s"]
        ok = c_s > 0
        a = np.zeros_like(c_s)
        a[ok] = attenuation(c_s[ok], tau)
        return side[key] * a

    def _channels(self, wavelengths):
        if wavelengths is None:
            return DEFAULT_WAVELENGTHS, srgb_weights(DEFAULT_WAVELENGTHS)
        wl = check.real_array("wavelengths", wavelengths, 0.0, lo_open=True)
        return np.atleast_1d(wl).ravel(), None

    def _at(self, lam: float) -> InterfaceAtWavelength:
        key = float(lam)
        at = self._optics.get(key)
        if at is None:
            if len(self._optics) >= _CACHE_LIMIT:
                self._optics.clear()
            layers = [(complex(layer.material.index(np.array([key]))[0]), layer.thickness_nm)
                      for layer in self.film]
            at = self._optics[key] = InterfaceAtWavelength(self.ext_ior, self.int_ior,
                                                           layers, key)
        return at

    def _spectral(self, lam: float) -> tuple[float, float, float, float]:
        """(rho, tau = sigma_a d, gamma, escape integral) at one wavelength (cached)."""
        key = float(lam)
        rho = float(self.base_reflectance.at(np.array([key]))[0])
        tau = float(self.sigma_a.at(np.array([key]))[0]) * self.thickness_um
        terms = self._terms.get(key)
        if terms is None:
            if len(self._terms) >= _CACHE_LIMIT:
                self._terms.clear()
            at = self._at(key)
            terms = self._terms[key] = (internal_return(at, tau), escape(at, tau))
        return (rho, tau, *terms)
