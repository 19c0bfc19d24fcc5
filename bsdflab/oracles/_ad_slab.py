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
azimuths (at least 4 per kept order, a power of two) and transformed by a real FFT;
Henyey-Greenstein is analytic in dphi in a strip of half-width
y = arccosh(1 + (1 - |g|)^2 / (2 |g|)), so its coefficients fall at least like exp(-m y)
and the aliasing of K samples is below exp(-y K / 2) (< 1e-13 for K >= 4 orders_needed).
"""
from __future__ import annotations

import numpy as np

from bsdflab.oracles import _ad_operators as op

MIN_AZIMUTH_SAMPLES = 64


def hg(cos_theta: np.ndarray, g: float) -> np.ndarray:
    """Henyey-Greenstein density over the sphere (g > 0 forward), as bsdflab's core."""
    d = 1.0 + g * g - 2.0 * g * cos_theta
    return (1.0 - g * g) / (4.0 * np.pi * d * np.sqrt(d))


def phase_orders(mu_out, mu_in, g: float, orders: int, same_hemisphere: bool) -> np.ndarray:
    """Fourier coefficients p^m(mu_out, mu_in) for broadcastable cosine arrays, shape
    (orders, *broadcast shape), so that p(dphi) = sum_m p^m cos(m dphi). g = 0 is
    isotropic (order 0 only)."""
    mo, mi = np.broadcast_arrays(np.asarray(mu_out, float), np.asarray(mu_in, float))
    out = np.zeros((orders,) + mo.shape)
    if g == 0.0:
        out[0] = 1.0 / (4.0 * np.pi)
        return out
    sign = 1.0 if same_hemisphere else -1.0
    so, si = np.sqrt(np.maximum(0.0, 1.0 - mo * mo)), np.sqrt(np.maximum(0.0, 1.0 - mi * mi))
    samples = max(MIN_AZIMUTH_SAMPLES, 1 << int(np.ceil(np.log2(4 * orders))))
    dphi = 2.0 * np.pi * np.arange(samples) / samples
    cos_t = (sign * mo * mi)[..., None] + (so * si)[..., None] * np.cos(dphi)
    c = np.fft.rfft(hg(np.clip(cos_t, -1.0, 1.0), g), axis=-1).real / samples
    m = min(orders, c.shape[-1])
    out[:m] = np.moveaxis(c[..., :m], -1, 0)
    out[1:m] *= 2.0
    return out


def orders_needed(g: float, tolerance: float, sine: float = 1.0) -> int:
    """Fourier orders after which Henyey-Greenstein's coefficients p^m(mu, mu') are below
    tolerance (relative to its largest) whenever one of the two sines is <= `sine`.

    cos Theta = a + b cos(dphi) with |a| + b <= 1 and b <= sine: the pole of
    (1 + g^2 - 2 g cos Theta)^(-3/2) lies at cosh(y) >= 1 + (1 - |g|)^2 / (2 |g| sine), so
    the coefficients fall like exp(-m y). Every term of the adding equations contains a
    factor with a query cosine, so the query directions' largest sine sets the decay."""
    if g == 0.0:
        return 1
    y = np.arccosh(1.0 + (1.0 - abs(g)) ** 2 / (2.0 * abs(g) * max(sine, 1e-12)))
    return int(np.ceil(-np.log(tolerance) / y)) + 2


def _single_scattering(mu_out, mu_in, omega, delta, g, orders):
    """Thin-layer kernels (reflection, transmission), each (L, M, *broadcast shape)."""
    mo, mi = np.broadcast_arrays(np.asarray(mu_out, float), np.asarray(mu_in, float))
    extra = (slice(None),) + (None,) * (mo.ndim + 1)
    d, w = np.asarray(delta, float)[extra], np.asarray(omega, float)[extra]
    refl = -np.expm1(-d * (1.0 / mo + 1.0 / mi)) / (mo + mi)
    x = 1.0 / mi - 1.0 / mo
    small = np.abs(d * x) < 1e-8
    safe_x = np.where(small, 1.0, x)
    h = np.where(small, d * (1.0 - 0.5 * d * x), -np.expm1(-d * safe_x) / safe_x)
    trans = np.exp(-d / mo) * h / (mo * mi)
    p_r = phase_orders(mo, mi, g, orders, same_hemisphere=False)
    p_t = phase_orders(mo, mi, g, orders, same_hemisphere=True)
    return w * p_r[None] * refl, w * p_t[None] * trans


def _unscattered(tau, mu_nodes, mu_out, mu_in):
    t = np.asarray(tau, float)[:, None, None]
    return (np.exp(-t / mu_nodes), np.exp(-t / mu_out), np.exp(-t / mu_in))


def thin_layer(cos, pr, pc, omega, delta, g, orders) -> op.LayerOperators:
    """Single-scattering layer of optical depths delta (L,) and albedos omega (L,) on
    cos = (nodes, outputs, inputs) with the requested pairs (pr, pc)."""
    mu, out, inp = cos
    blocks = [_single_scattering(a, b, omega, delta, g, orders)
              for a, b in ((mu[:, None], mu[None, :]), (out[:, None], mu[None, :]),
                           (mu[:, None], inp[None, :]), (out[pr], inp[pc]))]
    (rK, tK), (rKr, tKr), (rKc, tKc), (rKp, tKp) = blocks
    R = op.Operator(K=rK, Kr=rKr, Kc=rKc, Kp=rKp)
    T = op.Operator(*_unscattered(delta, mu, out, inp), K=tK, Kr=tKr, Kc=tKc, Kp=tKp)
    return op.LayerOperators(R, T, R, T)


def slab_layer(cos, grid: op.Grid, tau, omega, g, thin_depth) -> op.LayerOperators:
    """Operators of a slab of optical depths tau (L,) and albedos omega (L,), by
    doubling from a layer no thicker than thin_depth."""
    tau = np.asarray(tau, dtype=np.float64)
    omega = np.asarray(omega, dtype=np.float64)
    if not np.any(omega > 0):  # absorption only: the unscattered beam is exact
        T = op.Operator(*_unscattered(tau, *cos))
        return op.LayerOperators(op.Operator(), T, op.Operator(), T)
    doublings = max(0, int(np.ceil(np.log2(max(float(np.max(tau)), 1e-300) / thin_depth))))
    delta = tau / 2.0 ** doublings
    layer = thin_layer(cos, grid.pr, grid.pc, omega, delta, g, grid.batch[1])
    for k in range(1, doublings + 1):
        layer = op.double(layer, grid)
        # the unscattered beam exactly (2^28 products of exp(-delta / mu) lose 3e-8)
        d = layer.Td
        T = op.Operator(*_unscattered(delta * 2.0 ** k, *cos), d.K, d.Kr, d.Kc, d.Kp)
        layer = op.LayerOperators(layer.Rt, T, layer.Rb, T)
    return layer
