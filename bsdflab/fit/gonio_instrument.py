"""The instrument's angular and spectral terms on gonio rows of the full model (docs/fit.md,
"Structures for the full model"): where a solution is evaluated for each row, and with
which weights the values are averaged.

* ``angle_offset_deg`` delta: a sample tilt about the y axis (normal to the plane of
  incidence). Source and detector both rotate by it in the sample's frame: an in-plane row
  (theta_i, theta_o) is seen at (theta_i + delta, theta_o - delta), so a specular row's
  theta + offset of the smooth model is the same fact. A detector-arm zero offset (theta_o
  alone) is not modelled.
* ``acceptance_deg`` a: the illumination fills a cone of half-angle a around the source
  direction (the solver's ``wo``), uniform in solid angle; the detector is a point. This is
  the smooth model's cone (core/include/bsdflab/fit_instrument.h): Gauss-Legendre in the
  cone angle b on [0, a] with weight sin b, midpoints in its azimuth. A gonio row is not
  mirror-symmetric about the plane of incidence (the detector may lie out of it), so the
  azimuths cover [0, 2 pi): 2 x cone_azimuths midpoints, the smooth model's nodes and their
  mirror images.
* ``bandwidth_nm`` b: a Gaussian slit of FWHM b over wavelength, Gauss-Hermite nodes
  (bsdflab.fit.stack_forward.slit_nodes, the smooth model's).

On a ``total`` row (an integrating sphere) the same terms act on the incidence alone: the
tilt moves theta_i, the cone averages the directional-hemispherical reflectance
(bsdflab.fit.hemispherical) over the illumination's directions, the slit over wavelength.

The reported row is the weighted mean of pi f over the cone's and the slit's nodes (scale
and background are applied after, by the posterior). All nodes of all rows are evaluated at
once: one solve at the union of the slit's wavelengths, one ``Solution.eval`` of the
distinct (detector, source) pairs.
"""

from __future__ import annotations

import numpy as np

from bsdflab.fit.hemispherical import directional_albedo
from bsdflab.fit.stack_forward import FWHM_TO_SIGMA, cone_polar_nodes, slit_nodes

TERMS = ("angle_offset_deg", "acceptance_deg", "bandwidth_nm")


def tilt(v: np.ndarray, delta_deg: np.ndarray) -> np.ndarray:
    """Directions (rows, ..., 3) in the frame of a sample tilted by delta (rows,) about y:
    the source at -x moves from theta to theta + delta."""
    d = np.radians(delta_deg).reshape(-1, *([1] * (v.ndim - 2)))
    c, s = np.cos(d), np.sin(d)
    x, y, z = v[..., 0], v[..., 1], v[..., 2]
    return np.stack([x * c - z * s, y, x * s + z * c], axis=-1)


class GonioQuadrature:
    """Evaluation points and weights of rows (detector, source, wavelength) seen through the
    instrument terms; ``cone`` / ``slit`` False: that term is off for every row (one node)."""

    def __init__(
        self,
        detector,
        source,
        wavelength_nm,
        cone: bool,
        slit: bool,
        bandwidth_nodes: int,
        cone_polar: int,
        cone_azimuths: int,
        total=None,
    ):
        self.detector, self.source = np.asarray(detector, float), np.asarray(source, float)
        self.total = np.zeros(len(self.source), bool) if total is None else np.asarray(total, bool)
        self.wavelength_nm = np.asarray(wavelength_nm, float)
        self._x, self._w = slit_nodes(bandwidth_nodes) if slit else (np.zeros(1), np.ones(1))
        if cone:
            u, w = cone_polar_nodes(cone_polar)
            psi = 2 * np.pi * (np.arange(2 * cone_azimuths) + 0.5) / (2 * cone_azimuths)
            self._u, self._uw = np.repeat(u, len(psi)), np.repeat(w, len(psi))
            self._psi = np.tile(psi, len(u))
        else:
            self._u, self._uw, self._psi = np.zeros(1), np.ones(1), np.zeros(1)

    @property
    def nodes(self) -> int:
        """Evaluation points per row (cone x slit)."""
        return len(self._u) * len(self._x)

    def points(self, offset, acceptance, bandwidth):
        """Per row (offset, acceptance, bandwidth: (rows,)): detector (rows, 3), sources (rows,
        C, 3), cone weights (rows, C), wavelengths (rows, K), slit weights (K,); weights sum
        to 1. Rows whose tilted directions or cone reach the horizon are flagged in ``ok``."""
        det, src = tilt(self.detector, offset), tilt(self.source, offset)
        a = np.radians(acceptance)[:, None]
        b = a * self._u[None, :]
        wb = np.where(a > 0, self._uw[None, :] * np.sin(b), self._uw[None, :])
        # e1 in the plane of incidence, e2 = y: the cone's axes (the tilted source keeps y = 0)
        e1 = np.stack([src[:, 2], np.zeros(len(src)), -src[:, 0]], axis=-1)
        e2 = np.broadcast_to(np.array([0.0, 1.0, 0.0]), src.shape)
        radial = np.cos(self._psi)[None, :, None] * e1[:, None, :] + np.sin(self._psi)[None, :, None] * e2[:, None, :]
        sources = np.cos(b)[..., None] * src[:, None, :] + np.sin(b)[..., None] * radial
        sigma = np.asarray(bandwidth, float) * FWHM_TO_SIGMA
        wl = self.wavelength_nm[:, None] + np.sqrt(2.0) * sigma[:, None] * self._x[None, :]
        ok = (det[:, 2] > 0) & np.all(sources[..., 2] > 0, axis=1) & np.all(wl > 0, axis=1)
        ok &= (np.asarray(acceptance) >= 0) & (np.asarray(bandwidth) >= 0)  # NaN: False
        return det, sources, wb / wb.sum(axis=1, keepdims=True), wl, self._w / self._w.sum(), ok

    def pi_f(self, solve, offset, acceptance, bandwidth) -> np.ndarray:
        """The rows' mean pi f (rows,), for total rows the mean directional-hemispherical
        reflectance: ``solve(wavelengths)`` gives a solution at those wavelengths; NaN where
        ``points`` flags a row."""
        det, sources, wc, wl, wk, ok = self.points(offset, acceptance, bandwidth)
        out = np.full(len(det), np.nan)
        if not np.any(ok):
            return out
        waves = np.unique(wl[ok])
        sol = solve(waves)
        for rows in (ok & ~self.total, ok & self.total):
            if np.any(rows):
                out[rows] = self._mean(sol, waves, rows, det[rows], sources[rows], wc[rows], wl[rows], wk)
        return out

    def _mean(self, sol, waves, rows, det, sources, wc, wl, wk) -> np.ndarray:
        """Rows' weighted means over their cone and slit nodes (all gonio or all total rows):
        pi f of the distinct (detector, source) pairs, or the directional-hemispherical
        reflectance of the distinct source cosines (bsdflab.fit.hemispherical)."""
        n, cone = sources.shape[:2]
        wl_index = np.searchsorted(waves, wl).reshape(n, 1, -1)
        if np.all(self.total[rows]):
            mu, mu_index = np.unique(sources[..., 2], return_inverse=True)
            values = directional_albedo(sol, mu, waves)  # (cosines, wavelengths)
            return np.einsum("rck,rc,k->r", values[mu_index.reshape(n, cone)[:, :, None], wl_index], wc, wk)
        pairs = np.concatenate([np.repeat(det[:, None, :], cone, axis=1), sources], axis=-1).reshape(-1, 6)
        pairs, pair_index = np.unique(pairs, axis=0, return_inverse=True)
        wi, wo = np.ascontiguousarray(pairs[:, :3]), np.ascontiguousarray(pairs[:, 3:])
        values = np.pi * sol.eval(wi, wo) / wo[:, 2:3]  # (pairs, wavelengths)
        return np.einsum("rck,rc,k->r", values[pair_index.reshape(n, cone)[:, :, None], wl_index], wc, wk)
