r"""A homogeneous scattering slab by doubling (van de Hulst 1963; Jakob et al. 2014, sec. 4).

Start from a layer of optical depth delta = tau / 2^k so thin that single scattering
describes it to O(delta^2), then double it k times with ``_ad_operators.double``. The
thin layer's exact single-scattering kernels, for a downward beam at cosine mu' and an
exit at mu (omega the single-scattering albedo, p the phase function of the angle
between the propagation directions, normalised over the sphere):

    reflection    omega p (1 - exp(-delta (1/mu + 1/mu'))) / (mu + mu')
    transmission  omega p exp(-delta/mu) (1 - exp(-delta x)) / (x mu mu'),
                  x = 1/mu' - 1/mu   (-> omega p delta exp(-delta/mu) / mu^2 at x = 0)

and the unscattered beam exp(-delta/mu) as the delta part of the transmission. The
slab is up-down symmetric, so Rb = Rt and Tu = Td. The neglected multiple scattering
inside the thin layer is O((delta/mu)^2) per layer and O(tau delta / mu^2) after the
doublings; ``thin_depth`` bounds delta (convergence measured in
tests/test_oracle_adding_doubling.py).

Phase-function Fourier coefficients: p(cos Theta) with
cos Theta = +-mu mu' + sqrt(1 - mu^2) sqrt(1 - mu'^2) cos(dphi) (+ between two downward
directions, - between a downward and an upward one) is sampled at ``AZIMUTH_SAMPLES``
azimuths and transformed by a real FFT; Henyey-Greenstein is analytic in dphi in a strip
of half-width y = arccosh(1 + (1 - |g|)^2 / (2 |g|)), so its coefficients fall at least
like exp(-m y) and aliasing is below exp(-y AZIMUTH_SAMPLES / 2).
"""
from __future__ import annotations

import numpy as np

from . import _ad_operators as op

AZIMUTH_SAMPLES = 512


def hg(cos_theta: np.ndarray, g: float) -> np.ndarray:
    """Henyey-Greenstein density over the sphere (g > 0 forward), as bsdflab's core."""
    d = 1.0 + g * g - 2.0 * g * cos_theta
    return (1.0 - g * g) / (4.0 * np.pi * d * np.sqrt(d))


def phase_orders(mu: np.ndarray, g: float, orders: int, same_hemisphere: bool) -> np.ndarray:
    """Fourier coefficients p^m(mu_out, mu_in), shape (orders, N, N), so that
    p(dphi) = sum_m p^m cos(m dphi). g = 0 is isotropic (order 0 only)."""
    n = len(mu)
    out = np.zeros((orders, n, n))
    if g == 0.0:
        out[0] = 1.0 / (4.0 * np.pi)
        return out
    sign = 1.0 if same_hemisphere else -1.0
    s = np.sqrt(np.maximum(0.0, 1.0 - mu * mu))
    dphi = 2.0 * np.pi * np.arange(AZIMUTH_SAMPLES) / AZIMUTH_SAMPLES
    cos_t = (sign * mu[:, None, None] * mu[None, :, None]
             + s[:, None, None] * s[None, :, None] * np.cos(dphi))
    c = np.fft.rfft(hg(np.clip(cos_t, -1.0, 1.0), g), axis=-1).real / AZIMUTH_SAMPLES
    m = min(orders, c.shape[-1])
    out[:m] = np.moveaxis(c[..., :m], -1, 0)
    out[1:m] *= 2.0
    return out


def orders_needed(g: float, tolerance: float) -> int:
    """Fourier orders after which Henyey-Greenstein's coefficients are below tolerance
    (relative to its largest), from the analyticity strip (module docstring)."""
    if g == 0.0:
        return 1
    y = np.arccosh(1.0 + (1.0 - abs(g)) ** 2 / (2.0 * abs(g)))
    return int(np.ceil(-np.log(tolerance) / y)) + 2


def thin_layer(mu, omega, delta, p_reflect, p_transmit) -> op.Layer:
    """Single-scattering layer of optical depths delta (L,), albedos omega (L,) on nodes
    mu (N,), with phase orders (M, N, N); operators batched (L, M, N[, N])."""
    d = np.asarray(delta, dtype=np.float64)[:, None, None, None]
    w = np.asarray(omega, dtype=np.float64)[:, None, None, None]
    mo, mi = mu[:, None], mu[None, :]          # output rows, input columns
    inv_sum = 1.0 / mo + 1.0 / mi
    refl = -np.expm1(-d * inv_sum) / (mo + mi)
    x = 1.0 / mi - 1.0 / mo
    small = np.abs(d * x) < 1e-8
    safe_x = np.where(small, 1.0, x)
    h = np.where(small, d * (1.0 - 0.5 * d * x), -np.expm1(-d * safe_x) / safe_x)
    trans = np.exp(-d / mo) * h / (mo * mi)
    R = op.Operator(None, w * p_reflect[None] * refl)
    T = op.Operator(np.exp(-d[..., 0] / mu), w * p_transmit[None] * trans)
    return op.Layer(R, T, R, T)


def slab_layer(mu, W, tau, omega, g, orders, thin_depth) -> op.Layer:
    """Operators of a slab of optical depths tau (L,) and albedos omega (L,), by
    doubling from a layer no thicker than thin_depth."""
    tau = np.asarray(tau, dtype=np.float64)
    omega = np.asarray(omega, dtype=np.float64)
    shape = (len(tau), orders, len(mu))
    if not np.any(omega > 0):  # absorption only: the unscattered beam is exact
        T = op.Operator(np.exp(-tau[:, None, None] / mu), None)
        return op.Layer(op.zero(), T, op.zero(), T)
    doublings = max(0, int(np.ceil(np.log2(max(float(np.max(tau)), 1e-300) / thin_depth))))
    p_r = phase_orders(mu, g, orders, same_hemisphere=False)
    p_t = phase_orders(mu, g, orders, same_hemisphere=True)
    layer = thin_layer(mu, omega, tau / 2.0 ** doublings, p_r, p_t)
    for _ in range(doublings):
        layer = op.double(layer, W, shape)
    return layer
