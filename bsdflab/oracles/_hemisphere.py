"""Hemispherical integrals of the coated-diffuse oracle, by adaptive Gauss-Legendre
quadrature on the branches of ``_interface`` (where the integrands are smooth).

With the cosine-weighted measure (cos u / pi) d omega_u = 2 c dc and Snell's law
n_e^2 c_e dc_e = n_s^2 c_s dc_s, an integral over the transmitting branch in its
parameter p (the rarer medium's cosine) is (n_r / n_medium)^2 * int_0^1 2 p g dp, and the
slab's total-internal-reflection cone c_s in [0, c_crit], c_s = c_crit cos(phi), is
int_0^{pi/2} c_crit^2 sin(2 phi) g dphi. Splitting at the critical angle keeps the
square-root kink of the Fresnel terms out of every integrand.
"""
from __future__ import annotations

from collections.abc import Callable
from functools import cache

import numpy as np

from bsdflab.oracles._interface import InterfaceAtWavelength

TOLERANCE = 1e-14   # absolute change between successive node counts (integrals are <= 1)
FIRST_NODES = 16
MAX_NODES = 8192


@cache
def _nodes(n: int) -> tuple[np.ndarray, np.ndarray]:
    return np.polynomial.legendre.leggauss(n)


def integrate(f: Callable[[np.ndarray], np.ndarray], a: float, b: float) -> float:
    """int_a^b f, doubling the Gauss-Legendre nodes until two results agree to TOLERANCE.

    Raises
    ------
    RuntimeError
        When ``MAX_NODES`` nodes do not converge.
    """
    previous, n = None, FIRST_NODES
    while n <= MAX_NODES:
        x, w = _nodes(n)
        half = 0.5 * (b - a)
        value = float(half * (w @ f(a + half * (x + 1.0))))
        if previous is not None and abs(value - previous) <= TOLERANCE:
            return value
        previous, n = value, 2 * n
    raise RuntimeError(f"quadrature did not converge with {MAX_NODES} nodes")


def attenuation(c, tau: float) -> np.ndarray:
    """exp(-tau / c): transmittance of a slab of optical depth tau along cosine c > 0."""
    return np.exp(-tau / np.asarray(c, dtype=np.float64))


def internal_return(at: InterfaceAtWavelength, tau: float) -> float:
    """gamma: the fraction of a Lambertian emission at the base that the top sends back to
    the base, int (cos u / pi) exp(-2 tau / cos u) R_slab(u) d omega_u (TIR included)."""
    scale = (at.n_rare / at.n_slab) ** 2

    def escaping(p):
        return 2 * p * attenuation(at.pair(p)[1], 2 * tau) * at.transmitting(p)[:, 1]

    gamma = scale * integrate(escaping, 0.0, 1.0)
    if at.has_tir and at.ext_is_rare:  # the slab is denser: its TIR cone
        def trapped(phi):
            c_s = at.c_crit * np.cos(phi)
            return (at.c_crit ** 2 * np.sin(2 * phi) * attenuation(c_s, 2 * tau)
                    * at.tir_reflectance(phi))

        gamma += integrate(trapped, 0.0, np.pi / 2)
    return gamma


def escape(at: InterfaceAtWavelength, tau: float) -> float:
    """int (cos theta_o / pi) exp(-tau / cos theta_o') T_slab(theta_o') d omega_o over the
    exterior hemisphere: radiance leaving the base uniformly, attenuated once, carried out
    (before the 1/eta^2 of radiance compression)."""
    scale = (at.n_rare / at.n_ext) ** 2

    def leaving(p):
        return 2 * p * attenuation(at.pair(p)[1], tau) * at.transmitting(p)[:, 3]

    return scale * integrate(leaving, 0.0, 1.0)
