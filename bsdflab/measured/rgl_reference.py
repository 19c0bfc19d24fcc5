"""An RGL material evaluated in numpy, step by step as the format defines it (the writer's
yardstick for its error bound and the tests' second opinion on the C++ reader).

With u = (sqrt(2 theta / pi), (phi + pi) / 2 pi) the unit-square coordinates of a direction
and m = normalize(wi + wo) the half vector:

* eval(wi, wo) = values(s; phi_i, theta_i, channel) * [D(u_m) / (4 sigma(u_wi)) if jacobian]
  where s = VNDF^-1(u_m; phi_i, theta_i) -- the values live on the VNDF's unit square;
  it is f * cos(theta_o) (Mitsuba's eval), zero unless both directions are above the surface;
* pdf(wi, wo) = vndf(u_m) * luminance(s) / (2 pi^2 u_m.x sin(theta_m) * 4 (wi . m)), the
  Jacobians of u -> m (solid angle) and m -> wo (reflection);
* sample: s = luminance warp of the uniforms (u2.y, u2.x), u_m = VNDF warp of s, reflect.

Isotropic files (1-2 phi_i nodes) use the azimuth of m relative to wi's.
"""
from __future__ import annotations

import numpy as np

from bsdflab.measured.marginal import Marginal2D
from bsdflab.measured.rgl_file import RGLData

PI = np.pi


def theta2u(theta):
    return np.sqrt(np.maximum(theta, 0.0) * (2.0 / PI))


def u2theta(u):
    return u * u * (PI / 2.0)


def phi2u(phi):
    return (phi + PI) / (2.0 * PI)


def u2phi(u):
    return (2.0 * u - 1.0) * PI


def elevation(d):
    """theta of unit vectors d (N, 3), accurate near the pole."""
    dist = np.sqrt(d[:, 0] ** 2 + d[:, 1] ** 2 + (d[:, 2] - 1.0) ** 2)
    return 2.0 * np.arcsin(np.clip(0.5 * dist, -1.0, 1.0))


class RGLReference:
    """eval / pdf / sample of an ``RGLData`` (numpy, float64 arithmetic on float32 tables)."""

    def __init__(self, data: RGLData):
        self.data = data
        params = (data.phi_i, data.theta_i)
        self.ndf = Marginal2D(data.ndf, normalize=False)
        self.sigma = Marginal2D(data.sigma, normalize=False)
        self.vndf = Marginal2D(data.vndf, params)
        self.luminance = Marginal2D(data.luminance, params)
        channel_nodes = data.wavelengths if data.spectral else np.arange(3, dtype=np.float32)
        self.values = Marginal2D(data.values, (*params, channel_nodes), normalize=False)
        self.channel_nodes = np.asarray(channel_nodes, dtype=np.float64)

    def _frame(self, wi, wo):
        m = wi + wo
        m = m / np.maximum(np.linalg.norm(m, axis=1, keepdims=True), 1e-300)
        theta_i, phi_i = elevation(wi), np.arctan2(wi[:, 1], wi[:, 0])
        theta_m, phi_m = elevation(m), np.arctan2(m[:, 1], m[:, 0])
        u_wi = np.stack([theta2u(theta_i), phi2u(phi_i)], axis=1)
        u_m = np.stack([theta2u(theta_m), phi2u(phi_m - phi_i)], axis=1)
        u_m[:, 1] -= np.floor(u_m[:, 1])
        return m, (phi_i, theta_i), u_wi, u_m

    def _values(self, s, params, u_m, u_wi, channels):
        n = len(s)
        out = np.empty((n, len(channels)))
        for c, lam in enumerate(channels):
            out[:, c] = self.values.eval(s, (*params, np.full(n, lam)))
        if self.data.jacobian:
            out *= (self.ndf.eval(u_m) / (4.0 * self.sigma.eval(u_wi)))[:, None]
        return out

    def eval(self, wi, wo, channels=None):
        """f cos(theta_o), (N, C); ``channels`` are wavelengths (nm) for a spectral file,
        None for the file's own channels (RGB, or its wavelength nodes)."""
        wi, wo = np.asarray(wi, float), np.asarray(wo, float)
        channels = self.channel_nodes if channels is None else np.asarray(channels, float)
        m, params, u_wi, u_m = self._frame(wi, wo)
        s, _ = self.vndf.invert(u_m, params)
        out = self._values(s, params, u_m, u_wi, channels)
        active = (wi[:, 2] > 0) & (wo[:, 2] > 0)
        return np.where(active[:, None], out, 0.0)

    def pdf(self, wi, wo):
        wi, wo = np.asarray(wi, float), np.asarray(wo, float)
        m, params, u_wi, u_m = self._frame(wi, wo)
        s, vndf_pdf = self.vndf.invert(u_m, params)
        lum = self.luminance.eval(s, params)
        jac = _jacobian(u_m[:, 0], m, wi)
        active = (wi[:, 2] > 0) & (wo[:, 2] > 0)
        with np.errstate(divide="ignore", invalid="ignore"):
            pdf = vndf_pdf * lum / jac
        return np.where(active & np.isfinite(pdf), pdf, 0.0)

    def sample(self, wi, u2, channels=None):
        """(wo (N, 3), weight (N, C) = eval / pdf, pdf (N,)) for uniforms u2 (N, 2)."""
        wi, u2 = np.asarray(wi, float), np.asarray(u2, float)
        channels = self.channel_nodes if channels is None else np.asarray(channels, float)
        theta_i, phi_i = elevation(wi), np.arctan2(wi[:, 1], wi[:, 0])
        params = (phi_i, theta_i)
        u_wi = np.stack([theta2u(theta_i), phi2u(phi_i)], axis=1)
        s, lum_pdf = self.luminance.sample(u2[:, ::-1], params)
        u_m, vndf_pdf = self.vndf.sample(s, params)
        theta_m, phi_m = u2theta(u_m[:, 0]), u2phi(u_m[:, 1]) + phi_i
        m = np.stack([np.cos(phi_m) * np.sin(theta_m), np.sin(phi_m) * np.sin(theta_m), np.cos(theta_m)], axis=1)
        jac = np.maximum(2 * PI * PI * u_m[:, 0] * np.sin(theta_m), 1e-6) * 4 * np.sum(wi * m, axis=1)
        wo = 2 * np.sum(m * wi, axis=1, keepdims=True) * m - wi
        with np.errstate(divide="ignore", invalid="ignore"):
            pdf = vndf_pdf * lum_pdf / jac
            value = self._values(s, params, u_m, u_wi, channels)
            weight = value / pdf[:, None]
        ok = (wi[:, 2] > 0) & (wo[:, 2] > 0) & np.isfinite(pdf) & (pdf > 0)
        return wo, np.where(ok[:, None], weight, 0.0), np.where(ok, pdf, 0.0)


def _jacobian(u_x, m, wi):
    """d(solid angle of wo) / d(u_m): 2 pi^2 u sin(theta_m) (u -> m) times 4 (wi . m)."""
    sin_m = np.sqrt(np.maximum(1.0 - m[:, 2] ** 2, 0.0))
    return np.maximum(2 * PI * PI * u_x * sin_m, 1e-6) * 4 * np.sum(wi * m, axis=1)
