"""Unpolarised power reflectances and transmittances of the (coated) top interface,
computed by the independent ``tmm`` package (Byrnes), never by bsdflab's own optics.

Geometry. The exterior (real index n_e) lies above, the slab (real index n_s) below. A
ray crossing the interface has a cosine c_e outside and c_s inside, tied by Snell's law
n_e^2 (1 - c_e^2) = n_s^2 (1 - c_s^2) (film layers conserve n sin theta and do not change
this pair). The pairs form two branches, each parametrised so that every quantity is an
analytic function of its parameter (which is what makes Chebyshev interpolation and
Gauss-Legendre quadrature converge geometrically):

* transmitting branch: p in [0, 1], the cosine in the *rarer* medium; the cosine in the
  denser one, sqrt(1 - (n_r/n_d)^2 (1 - p^2)), stays >= cos(critical) > 0 and is analytic.
  Quantities: R_ext, R_slab (reflectance seen from outside / from the slab), T_ext,
  T_slab (transmittance for light arriving from outside / from the slab).
* total internal reflection (n_e != n_s only), seen from the denser medium: phi in
  [0, pi/2] with c_dense = c_crit cos(phi); the rarer medium's cosine is then
  i sqrt((n_d/n_r)^2 - 1) sin(phi), so R_dense(phi) is analytic where R(c_dense) has a
  square-root kink at the critical angle. R_dense = 1 for a bare interface or a lossless film, < 1
  under an absorbing film (the evanescent wave is absorbed in it).

Bare interface: tmm's vectorisable Fresnel helpers (interface_r/t, R_from_r, T_from_t)
are evaluated directly (exact). Coated interface: tmm.coh_tmm, scalar per angle, sampled
at Chebyshev points and interpolated (``_chebyshev.Chebyshev``, absolute error <= 1e-13
plus tmm's own error). tmm turns every angle into n sin(theta) and back through arcsin, so
the cosine it uses in the rarer medium carries an absolute error ~1e-16 / |c_rare|: its
R and T are off by up to ~3e-16 / |c_rare| within a few degrees of grazing in the rarer
medium (measured against the exact bare-interface formulas). The interpolation allows for
that (``TMM_NOISE``); integrals weight it by the cosine, where it is negligible.
"""
from __future__ import annotations

import numpy as np
import tmm

from ._chebyshev import Chebyshev

POLARISATIONS = ("s", "p")
TMM_NOISE = 1e-15  # bound on tmm's absolute error times |cos| in the rarer medium (3x measured)


class InterfaceAtWavelength:
    """R and T of the interface at one wavelength, as vectorised functions.

    Parameters
    ----------
    n_ext, n_slab : float
        Real indices of the exterior and the slab (> 0).
    layers : sequence of (complex index, thickness in nm)
        The coating, exterior side first; empty for a bare interface.
    wavelength_nm : float
        Vacuum wavelength in nm.
    """

    def __init__(self, n_ext: float, n_slab: float, layers, wavelength_nm: float):
        self.n_ext, self.n_slab = float(n_ext), float(n_slab)
        self.n_rare, self.n_dense = sorted((self.n_ext, self.n_slab))
        self.ext_is_rare = self.n_ext <= self.n_slab
        # cosine of the critical angle in the denser medium (0 when index-matched)
        self.c_crit = float(np.sqrt(1.0 - (self.n_rare / self.n_dense) ** 2))
        self.has_tir = self.n_ext != self.n_slab
        if layers:
            stack = _Stack(self.n_ext, self.n_slab, layers, wavelength_nm)
            self._trans = Chebyshev(lambda p: stack.transmitting(*self.pair(p)), 0.0, 1.0,
                                    noise=lambda p: TMM_NOISE / p)
            self._tir = (Chebyshev(lambda phi: stack.tir(self.ext_is_rare, self._dense(phi)),
                                   0.0, np.pi / 2, noise=self._tir_noise)
                         if self.has_tir else None)
        else:
            self._trans = lambda p: _bare(self.n_ext, self.n_slab, *self.pair(p))
            self._tir = lambda phi: np.ones((len(phi), 1))

    # -- geometry ------------------------------------------------------------------------
    def pair(self, p) -> tuple[np.ndarray, np.ndarray]:
        """(c_e, c_s) on the transmitting branch for rarer-medium cosines p."""
        p = np.asarray(p, dtype=np.float64)
        other = np.sqrt(1.0 - (self.n_rare / self.n_dense) ** 2 * (1.0 - p * p))
        return (p, other) if self.ext_is_rare else (other, p)

    def _dense(self, phi) -> np.ndarray:
        return self.c_crit * np.cos(phi)

    def _tir_noise(self, phi) -> np.ndarray:
        # |c_rare| = sqrt((n_d/n_r)^2 - 1) sin(phi) on this branch
        return TMM_NOISE / (np.sqrt((self.n_dense / self.n_rare) ** 2 - 1.0) * np.sin(phi))

    def rare_cosine(self, c_ext) -> tuple[np.ndarray, np.ndarray]:
        """For exterior cosines in (0, 1]: (p, transmits). Where light from outside is
        totally reflected (exterior denser, c_ext < c_crit), transmits is False and p 0."""
        c = np.asarray(c_ext, dtype=np.float64)
        if self.ext_is_rare:
            return c, np.ones(c.shape, dtype=bool)
        s2 = 1.0 - (self.n_ext / self.n_slab) ** 2 * (1.0 - c * c)
        ok = s2 > 0.0
        return np.sqrt(np.where(ok, s2, 0.0)), ok

    # -- powers ----------------------------------------------------------------------------
    def transmitting(self, p) -> np.ndarray:
        """(M, 4) columns R_ext, R_slab, T_ext, T_slab at rarer-medium cosines p in (0, 1]."""
        return self._trans(np.asarray(p, dtype=np.float64))

    def tir_reflectance(self, phi) -> np.ndarray:
        """(M,) reflectance from the denser medium beyond the critical angle,
        c_dense = c_crit cos(phi), phi in [0, pi/2)."""
        return self._tir(np.asarray(phi, dtype=np.float64))[:, 0]

    def from_exterior(self, c_ext) -> dict[str, np.ndarray]:
        """For exterior cosines c_ext in (0, 1] (M,): slab cosine ``c_s`` (0 where none),
        ``R_ext``, ``T_ext`` and ``T_slab`` (the latter for the reverse ray, arriving from
        the slab at c_s)."""
        c = np.asarray(c_ext, dtype=np.float64)
        p, ok = self.rare_cosine(c)
        out = {k: np.zeros(c.shape) for k in ("c_s", "R_ext", "T_ext", "T_slab")}
        if np.any(ok):
            v = self.transmitting(p[ok])
            out["c_s"][ok] = self.pair(p[ok])[1]
            out["R_ext"][ok], out["T_ext"][ok], out["T_slab"][ok] = v[:, 0], v[:, 2], v[:, 3]
        if np.any(~ok):  # exterior denser, beyond its critical angle
            phi = np.arccos(np.clip(c[~ok] / self.c_crit, 0.0, 1.0))
            out["R_ext"][~ok] = self.tir_reflectance(phi)
        return out


def _bare(n_e, n_s, c_e, c_s) -> np.ndarray:
    """(M, 4) R_ext, R_slab, T_ext, T_slab of a bare interface from tmm's Fresnel helpers
    (vectorised; angles enter them only through cos)."""
    th_e, th_s = np.arccos(c_e.astype(complex)), np.arccos(c_s.astype(complex))
    cols = np.zeros((len(c_e), 4))
    with np.errstate(divide="ignore", invalid="ignore"):  # 0/0 only at exact grazing
        for pol in POLARISATIONS:
            r_es = tmm.interface_r(pol, n_e, n_s, th_e, th_s)
            r_se = tmm.interface_r(pol, n_s, n_e, th_s, th_e)
            t_es = tmm.interface_t(pol, n_e, n_s, th_e, th_s)
            t_se = tmm.interface_t(pol, n_s, n_e, th_s, th_e)
            cols += 0.5 * np.stack([tmm.R_from_r(r_es), tmm.R_from_r(r_se),
                                    tmm.T_from_t(pol, t_es, n_e, n_s, th_e, th_s),
                                    tmm.T_from_t(pol, t_se, n_s, n_e, th_s, th_e)], axis=1)
    return np.nan_to_num(cols)


class _Stack:
    """tmm.coh_tmm for the coated interface, one angle per call."""

    def __init__(self, n_e, n_s, layers, wavelength_nm):
        self.down = [complex(n_e), *(complex(n) for n, _ in layers), complex(n_s)]
        self.d_down = [np.inf, *(float(d) for _, d in layers), np.inf]
        self.wl = float(wavelength_nm)

    def _solve(self, pol, from_ext, cos0):
        n, d = (self.down, self.d_down) if from_ext else (self.down[::-1], self.d_down[::-1])
        return tmm.coh_tmm(pol, n, d, float(np.arccos(cos0)), self.wl)

    def transmitting(self, c_e, c_s) -> np.ndarray:
        out = np.zeros((len(c_e), 4))
        for i, (ce, cs) in enumerate(zip(c_e, c_s)):
            for pol in POLARISATIONS:
                down, up = self._solve(pol, True, ce), self._solve(pol, False, cs)
                out[i] += 0.5 * np.array([down["R"], up["R"], down["T"], up["T"]])
        return out

    def tir(self, ext_is_rare, c_dense) -> np.ndarray:
        """Reflectance from the denser medium (the slab when ext_is_rare) at c_dense."""
        out = np.zeros((len(c_dense), 1))
        for i, c in enumerate(c_dense):
            out[i, 0] = 0.5 * sum(self._solve(pol, not ext_is_rare, c)["R"]
                                  for pol in POLARISATIONS)
        return out
