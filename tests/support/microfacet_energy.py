"""Single-scattering energy of a rough interface by quadrature (numpy only): the reference
for the white-furnace tests of RoughConductor / RoughDielectric.

With separable Smith shadowing G = G1(wi, m) G1(wo, m) (Walter et al. 2007, Mitsuba's and
bsdflab's model), the energy a rough interface scatters from wi -- reflection plus
transmission with the radiance scaling undone -- is an expectation over the visible
normals m ~ D_wi(m) = G1(wi, m) max(0, wi.m) D(m) / cos_i (Heitz 2014):

    E(wi) = E_m[ F(wi.m) G1(wr, m) + (1 - F(wi.m)) G1(wt, m) ]

with wr the mirror direction and wt the refracted one about m (F = 1 for a perfect-mirror
conductor). The integral over m runs in slope space, s = tan(theta_m) / alpha mapped to
x = s / (1 + s) in [0, 1) with Gauss-Legendre nodes, phi with equally spaced nodes;
the integrand has kinks (the visibility and side tests), so `energy_with_error` states
the quadrature error as the change from n to 2n nodes per axis.
"""
from __future__ import annotations

import numpy as np
from scipy.special import erf

from bsdflab.optics import fresnel_reflectance


def smith_lambda(dist: str, alpha: float, cos_theta: np.ndarray) -> np.ndarray:
    """Smith's Lambda of a direction with |cos theta| = cos_theta (GGX or Beckmann)."""
    c = np.clip(np.abs(cos_theta), 1e-300, 1.0)
    tan = np.sqrt(np.maximum(0.0, 1.0 - c * c)) / c
    if dist == "ggx":
        return 0.5 * (np.sqrt(1.0 + (alpha * tan) ** 2) - 1.0)
    with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
        a = 1.0 / (alpha * tan)
        lam = 0.5 * (erf(a) - 1.0) + np.exp(-a * a) / (2.0 * a * np.sqrt(np.pi))
    return np.where(tan == 0, 0.0, lam)


def _g1(dist, alpha, v, m):
    """G1(v, m) with the side test: m must face v on v's side of the macro-surface."""
    vm = np.einsum("...i,...i->...", v, m)
    ok = vm * v[..., 2] > 0
    return np.where(ok, 1.0 / (1.0 + smith_lambda(dist, alpha, v[..., 2])), 0.0)


def _normals(dist, alpha, n):
    """Microfacet normals and their weights D(m) dw_m on an n x n slope-space grid."""
    x, wx = np.polynomial.legendre.leggauss(n)
    x, wx = 0.5 * (x + 1.0), 0.5 * wx
    s = x / (1.0 - x)
    ds = wx / (1.0 - x) ** 2
    phi = (np.arange(n) + 0.5) * (2.0 * np.pi / n)
    shape = s * np.sqrt(1.0 + (alpha * s) ** 2) / np.pi  # D dw_m / (ds dphi), slope form
    shape = shape * (1.0 / (1.0 + s * s) ** 2 if dist == "ggx" else np.exp(-s * s))
    tan = alpha * s
    cos_m = 1.0 / np.sqrt(1.0 + tan * tan)
    sin_m = tan * cos_m
    m = np.stack([np.outer(sin_m, np.cos(phi)), np.outer(sin_m, np.sin(phi)),
                  np.outer(cos_m, np.ones(n))], axis=-1)
    w = np.outer(shape * ds, np.full(n, 2.0 * np.pi / n))
    return m, w


def _refracted_cos(cos_i, eta):
    """cos theta_t by Snell's law for eta = n_t / n_i; 0 under total internal reflection."""
    return np.sqrt(np.maximum(0.0, 1.0 - (1.0 - cos_i * cos_i) / (eta * eta)))


def energy(dist: str, alpha: float, wi, eta: float | None = None, n: int = 512) -> float:
    """Scattered energy fraction from direction ``wi`` (unit, either side): a perfect-mirror
    conductor when ``eta`` is None, else a dielectric with interior/exterior index ratio
    ``eta`` (interior below, z < 0)."""
    wi = np.asarray(wi, float)
    flip = wi[2] < 0
    up = wi * [1.0, 1.0, -1.0] if flip else wi
    rel = None if eta is None else (1.0 / eta if flip else eta)  # n_t / n_i seen from wi
    m, w = _normals(dist, alpha, n)
    wim = m @ up
    visible = _g1(dist, alpha, np.broadcast_to(up, m.shape), m) * np.maximum(wim, 0.0) / up[2]
    wr = 2.0 * wim[..., None] * m - up
    g_r = _g1(dist, alpha, wr, m)
    if rel is None:
        return float(np.sum(w * visible * g_r))
    cos_i = np.clip(wim, 0.0, 1.0)
    cos_t = _refracted_cos(cos_i, rel)
    F = np.where(cos_t > 0, fresnel_reflectance(cos_i, 1.0, rel).unpolarised, 1.0)  # checked against tmm
    wt = (wim / rel - cos_t)[..., None] * m - up / rel
    g_t = np.where(cos_t > 0, _g1(dist, alpha, wt, m), 0.0)
    return float(np.sum(w * visible * (F * g_r + (1.0 - F) * g_t)))


def energy_with_error(dist: str, alpha: float, wi, eta: float | None = None, n: int = 512):
    """(energy, quadrature error bound): the 2n-node value and |E(2n) - E(n)|."""
    coarse, fine = energy(dist, alpha, wi, eta, n), energy(dist, alpha, wi, eta, 2 * n)
    return fine, abs(fine - coarse)
