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
  square-root kink at the critical angle. R_dense = 1 for a bare interface or a lossless
  film, < 1 under an absorbing film (the evanescent wave is absorbed in it).

Bare interface: tmm's vectorisable Fresnel helpers (interface_r/t, R_from_r, T_from_t)
are evaluated directly at our cosines (exact). Coated interface: tmm.coh_tmm, scalar per
angle, sampled at Chebyshev points and interpolated (``_chebyshev.Chebyshev``, absolute
error <= 1e-13). tmm turns the angle into n sin(theta) and back through arcsin, so the
cosine it really uses in the rarer medium differs from the requested one by ~1e-16 /
|c_rare| (2e-12 in R and T at 0.01 degrees from grazing). Its results are exact for the
cosines it used, which it returns (``th_list``): the samples are placed there, and T is
recomputed from t with those angles (``tmm.T_from_t``; coh_tmm divides by the requested
cosine). Measured against the exact bare formulas this leaves ~1e-16.
"""
from __future__ import annotations

import numpy as np
import tmm

from bsdflab.oracles._chebyshev import Chebyshev

POLARISATIONS = ("s", "p")


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
        r = self.n_rare / self.n_dense
        self.c_crit = float(np.sqrt((1.0 - r) * (1.0 + r)))
        self.has_tir = self.n_ext != self.n_slab
        if layers:
            stack = _Stack(self, layers, wavelength_nm)
            down = Chebyshev(lambda p: stack.transmitting(p, from_ext=True), 0.0, 1.0)
            up = Chebyshev(lambda p: stack.transmitting(p, from_ext=False), 0.0, 1.0)
            self._fits = (down, up)
            # columns R_ext, R_slab, T_ext, T_slab from (R, T) seen from each side
            self._trans = lambda p: np.concatenate([down(p), up(p)], axis=1)[:, [0, 2, 1, 3]]
            self._tir = Chebyshev(stack.tir, 0.0, np.pi / 2) if self.has_tir else None
        else:
            self._trans = lambda p: _bare(self.n_ext, self.n_slab, *self.pair(p))
            self._tir = lambda phi: np.ones((len(phi), 1))

    # -- geometry ------------------------------------------------------------------------
    def pair(self, p) -> tuple[np.ndarray, np.ndarray]:
        """(c_e, c_s) on the transmitting branch for rarer-medium cosines p."""
        p = np.asarray(p, dtype=np.float64)
        # 1 - r^2 (1 - p^2) written without cancellation
        other = np.sqrt(self.c_crit ** 2 + (self.n_rare / self.n_dense * p) ** 2)
        return (p, other) if self.ext_is_rare else (other, p)

    def rare_cosine(self, c_ext) -> tuple[np.ndarray, np.ndarray]:
        """For exterior cosines in (0, 1]: (p, transmits). Where light from outside is
        totally reflected (exterior denser, c_ext < c_crit), transmits is False and p 0."""
        c = np.asarray(c_ext, dtype=np.float64)
        if self.ext_is_rare:
            return c, np.ones(c.shape, dtype=bool)
        # c_s^2 = 1 - (n_e/n_s)^2 (1 - c^2) = (n_e/n_s)^2 (c - c_crit)(c + c_crit)
        ok = c > self.c_crit
        s2 = (self.n_ext / self.n_slab) ** 2 * (c - self.c_crit) * (c + self.c_crit)
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
    """tmm.coh_tmm for the coated interface, one angle per call, as samplers for
    ``Chebyshev``: each returns the branch parameter tmm really used and (R, T)."""

    def __init__(self, at: InterfaceAtWavelength, layers, wavelength_nm):
        self.at = at
        self.down = [complex(at.n_ext), *(complex(n) for n, _ in layers), complex(at.n_slab)]
        self.d_down = [np.inf, *(float(d) for _, d in layers), np.inf]
        self.wl = float(wavelength_nm)

    def _solve(self, pol, from_ext, cos0):
        """(R, T, cosines tmm used in the incident and exit media)."""
        n, d = (self.down, self.d_down) if from_ext else (self.down[::-1], self.d_down[::-1])
        res = tmm.coh_tmm(pol, n, d, float(np.arccos(cos0)), self.wl)
        th = res["th_list"]
        # T from t with the angles tmm used for t (coh_tmm divides by the requested cos)
        t = tmm.T_from_t(pol, res["t"], n[0], n[-1], th[0], th[-1])
        return res["R"], t, np.cos(th[0]), np.cos(th[-1])

    def transmitting(self, p, *, from_ext: bool):
        """Rarer-medium cosines p (M,) -> (p actually used (M,), (M, 2) R and T) for light
        arriving from the exterior (from_ext) or from the slab."""
        c_e, c_s = self.at.pair(p)
        used, out = np.empty(len(p)), np.zeros((len(p), 2))
        rare_is_incident = from_ext == self.at.ext_is_rare
        for i, c in enumerate(c_e if from_ext else c_s):
            for pol in POLARISATIONS:
                r, t, c_in, c_exit = self._solve(pol, from_ext, c)
                out[i] += 0.5 * np.array([r, t])
            used[i] = (c_in if rare_is_incident else c_exit).real
        return used, out

    def tir(self, phi):
        """phi (M,) -> (phi actually used, (M, 1) reflectance from the denser medium)."""
        k = np.sqrt((self.at.n_dense / self.at.n_rare) ** 2 - 1.0)  # |c_rare| = k sin(phi)
        used, out = np.empty(len(phi)), np.zeros((len(phi), 1))
        for i, c in enumerate(self.at.c_crit * np.cos(phi)):
            for pol in POLARISATIONS:
                r, _, c_in, c_exit = self._solve(pol, not self.at.ext_is_rare, c)
                out[i, 0] += 0.5 * r
            # sin(phi) = |c_rare| / k, cos(phi) = c_dense / c_crit; atan2 stays well
            # conditioned at both ends, where one of the two cosines is ill-determined
            used[i] = np.arctan2(abs(c_exit.imag) / k, c_in.real / self.at.c_crit)
        return used, out
