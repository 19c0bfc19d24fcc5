r"""Directional-hemispherical reflectance of a solved stack (the full model's ``total`` rows):
R(s, lambda) = \int_{H+} f(d, s) cos(theta_d) d omega_d, light arriving from s, the top's
own reflection included (docs/fit.md, "Total rows of the full model").

Split so that each part meets a rule fitted to its shape:

* the light that entered the stack (``Solution.eval(scattered_only=True)``, smooth over the
  hemisphere): a product rule, Gauss-Legendre in cos(theta_d) on [0, 1] times midpoints in
  the azimuth on [0, pi] (the stack is isotropic, so the integrand is even in the azimuth).
* the rough top's own reflection (a microfacet lobe of width ~ alpha around the mirror
  direction, ``Layered.exact_part``'s eval): integrated over the half vector h, d = 2 (s.h) h
  - s, d omega_d = 4 (d.h) d omega_h. With u the cumulative D(h) cos(theta_h) in theta_h
  (GGX: tan^2 = alpha^2 u / (1 - u); Beckmann: tan^2 = -alpha^2 ln(1 - u)) the lobe is
  uniform in u whatever alpha is, and the integrand F G (s.h) / (cos theta_s cos theta_h)
  is smooth. d stays above the horizon for theta_h < pi/4 + beta/2, beta = atan2(s_x cos
  phi_h, cos theta_s) (d.z = |.| cos(2 theta_h - beta)): per azimuth, Gauss-Legendre in u up
  to u = 0.9, then in ln tan(theta_h) up to that bound (u crowds the tail into a sliver next
  to u = 1; GGX's tail is a power law, an exponential in ln tan); midpoints in the azimuth
  on [0, pi].

The fit's full model has a rough top (roughness in [1e-3, 1]), so there is no delta lobe to
add. Accuracy at the default node counts (tests/fit/test_hemispherical.py): the top's part
within 1e-5 of a brute 1000 x 600 midpoint grid over the detector's hemisphere, the whole
within Monte Carlo noise of the model's own importance sampling (``Layered.sample``), and
the rule's change to a 4x denser one below 1e-5 (the snake's structure, 0-70 deg); a
sphere's noise is ~1e-3. Cost: 288 + 384 evaluations per distinct incidence, all
wavelengths at once.
"""

from __future__ import annotations

import numpy as np

from bsdflab.lobes import Lobe

SCATTER_NODES = (24, 12)  # Gauss-Legendre in cos(theta_d), midpoints in the azimuth on [0, pi]
TOP_NODES = (16, 12)  # Gauss-Legendre per panel (u, then theta_h), midpoints in the azimuth
U_SPLIT = 0.9  # the u panel holds 90 % of the normals (GGX: tan = 3 alpha; Beckmann: 1.52 alpha)
MAX_INCIDENCE_DEG = 85.0  # beyond, the top's horizon bound reaches the lobe's far tail


def _tan2(u: np.ndarray, alpha: float, distribution: str) -> np.ndarray:
    if distribution == "beckmann":
        return -(alpha**2) * np.log1p(-u)
    return alpha**2 * u / (1.0 - u)


def _cdf(tan2: np.ndarray, alpha: float, distribution: str) -> np.ndarray:
    if distribution == "beckmann":
        return -np.expm1(-tan2 / alpha**2)
    return tan2 / (alpha**2 + tan2)


def _density(tan2: np.ndarray, cos_h: np.ndarray, alpha: float, distribution: str) -> np.ndarray:
    """D(h) cos(theta_h), the normals' distribution projected (integrates to 1)."""
    c4 = cos_h**4
    if distribution == "beckmann":
        d = np.exp(-tan2 / alpha**2) / (np.pi * alpha**2 * c4)
    else:
        d = alpha**2 / (np.pi * c4 * (alpha**2 + tan2) ** 2)
    return d * cos_h


def _sources(mu: np.ndarray) -> np.ndarray:
    mu = np.asarray(mu, float)
    return np.column_stack([-np.sqrt(1.0 - mu**2), np.zeros_like(mu), mu])


def scatter_nodes(n_mu: int = SCATTER_NODES[0], n_phi: int = SCATTER_NODES[1]):
    """Detector directions (N, 3) and weights (N,) of the product rule: sum w g(d) ~ the
    integral of g(d) cos(theta_d) over the hemisphere, for g even in the azimuth."""
    x, w = np.polynomial.legendre.leggauss(n_mu)
    mu, wmu = 0.5 * (x + 1.0), 0.5 * w
    phi = np.pi * (np.arange(n_phi) + 0.5) / n_phi
    m, p = np.repeat(mu, n_phi), np.tile(phi, n_mu)
    s = np.sqrt(1.0 - m**2)
    d = np.column_stack([s * np.cos(p), s * np.sin(p), m])
    weights = np.repeat(wmu * mu, n_phi) * (2.0 * np.pi / n_phi)
    return d, weights


def top_nodes(mu, alpha: float, distribution: str, n_u: int = TOP_NODES[0], n_phi: int = TOP_NODES[1]):
    """Detector directions (A, N, 3) and weights (A, N) for sources at cos(theta) = mu (A,):
    the top's reflectance is sum_n w[a, n] * eval(d[a, n], s[a]) / mu[a] (eval: f |cos
    theta_s|, as ``Solution.eval``). Two panels in theta_h per azimuth: the lobe's own measure
    u up to U_SPLIT, then ln tan(theta_h) up to the horizon bound (u crowds the tail into a
    sliver next to u = 1 that Gauss-Legendre resolves slowly)."""
    mu = np.atleast_1d(np.asarray(mu, float))
    s = _sources(mu)
    x, wx = np.polynomial.legendre.leggauss(n_u)
    x, wx = 0.5 * (x + 1.0), 0.5 * wx  # on [0, 1]
    phi = np.pi * (np.arange(n_phi) + 0.5) / n_phi
    beta = np.arctan2(s[:, 0:1] * np.cos(phi)[None, :], mu[:, None])  # (A, n_phi): s.h = |.| cos(theta_h - beta)
    t_max = np.pi / 4 + beta / 2
    t_split = np.minimum(np.arctan(np.sqrt(_tan2(np.array(U_SPLIT), alpha, distribution))), t_max)
    u_split = _cdf(np.tan(t_split) ** 2, alpha, distribution)
    # panel 1 (in u): d omega_h = du dphi / (2 pi D cos theta_h)
    u = x * u_split[..., None]  # (A, n_phi, n_u)
    tan2_1 = _tan2(u, alpha, distribution)
    cos_1 = 1.0 / np.sqrt(1.0 + tan2_1)
    w1 = wx * u_split[..., None] / (2.0 * np.pi * _density(tan2_1, cos_1, alpha, distribution))
    # panel 2 (in v = ln tan theta_h: the tails' power law is an exponential there):
    # d omega_h = sin theta_h d theta_h d phi = sin^2 theta_h cos theta_h dv d phi
    v0, v1 = np.log(np.tan(t_split)), np.log(np.tan(t_max))
    t2 = np.arctan(np.exp(v0[..., None] + x * (v1 - v0)[..., None]))
    cos_2 = np.cos(t2)
    w2 = wx * (v1 - v0)[..., None] * np.sin(t2) ** 2 * cos_2
    cos_h = np.concatenate([cos_1, cos_2], axis=-1)
    sin_h = np.sqrt(np.maximum(1.0 - cos_h**2, 0.0))
    w_h = np.concatenate([w1, w2], axis=-1) * (2.0 * np.pi / n_phi)  # x2: the azimuth on [0, pi]
    ph = phi[None, :, None]
    h = np.stack(np.broadcast_arrays(sin_h * np.cos(ph), sin_h * np.sin(ph), cos_h), axis=-1)
    sh = np.einsum("apuk,ak->apu", h, s)
    d = 2.0 * sh[..., None] * h - s[:, None, None, :]
    d[..., 2] = np.maximum(d[..., 2], 1e-12)  # the bound's round-off
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    w = w_h * 4.0 * sh * d[..., 2]  # d omega_d = 4 (d.h) d omega_h, times cos(theta_d)
    return d.reshape(len(mu), -1, 3), w.reshape(len(mu), -1)


def directional_albedo(sol, mu, wavelengths, scatter=SCATTER_NODES, top=TOP_NODES) -> np.ndarray:
    """R (A, C): the directional-hemispherical reflectance of solution ``sol`` (its model a
    ``Layered`` with a rough top) for light arriving at cos(theta) = mu (A,), at the
    solution's wavelengths ``wavelengths`` (C,). One ``Solution.eval`` of the scattered part
    and one eval of the top over all sources and nodes."""
    mu = np.atleast_1d(np.asarray(mu, float))
    if np.any(~(mu >= np.cos(np.radians(MAX_INCIDENCE_DEG)))) or np.any(mu > 1):
        raise ValueError(f"total rows: incidence must lie in [0, {MAX_INCIDENCE_DEG:g}] deg")
    src = _sources(mu)
    a = len(mu)
    d, w = scatter_nodes(*scatter)
    n = len(d)
    wi = np.tile(d, (a, 1))
    wo = np.repeat(src, n, axis=0)
    scattered = sol.eval(wi, wo, scattered_only=True).reshape(a, n, -1)
    out = np.einsum("anc,n->ac", scattered, w) / mu[:, None]
    interface = sol.model.exact_part
    td, tw = top_nodes(mu, interface.alpha, interface.distribution, *top)
    k = td.shape[1]
    own = interface.eval(
        td.reshape(-1, 3), np.repeat(src, k, axis=0), wavelengths=np.asarray(wavelengths, float), lobes=Lobe.REFLECTION
    )
    return out + np.einsum("akc,ak->ac", own.reshape(a, k, -1), tw) / mu[:, None]
