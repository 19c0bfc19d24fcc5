r"""Scattering operators of the adding-doubling oracle and the adding equations.

Discretisation. Radiance on one hemisphere of the slab medium is a vector over cosine
nodes mu_j (quadrature weights w_j; zero-weight "query" nodes carry the directions a
caller asked about, so that the operators are known there exactly: Nystrom extension).
Azimuth is expanded in a cosine series of the propagation-azimuth difference,
f = sum_m f^m(mu_out, mu_in) cos(m dphi). Order m of an operator acts as

    (O L)_i = D_i L_i + sum_j K_ij W_j L_j,    W_j = pi (1 + [m = 0]) mu_j w_j,

where D is its delta part (unscattered transmission, specular reflection: the same in
every order) and K its kernel (the Fourier coefficient of f, output row, input column).
Keeping D and K apart makes every product and inverse below exact in the zero-weight
rows and columns:

    (D1 + K1 W)(D2 + K2 W) = D1 D2 + (D1 K2 + K1 D2 + K1 W K2) W,
    (I - D - K W)^-1       = G + (X G) W,   G = (I - D)^-1,   X = (I - G K W)^-1 G K.

Arrays carry leading batch axes (wavelength, Fourier order): D (..., N), K (..., N, N),
W (M, N) broadcast over them.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Operator:
    """D + K W: delta part D (..., N), kernel K (..., N, N); None means zero."""

    D: np.ndarray | None
    K: np.ndarray | None


def zero() -> Operator:
    return Operator(None, None)


def identity(shape) -> Operator:
    return Operator(np.ones(shape), None)


def add(a: Operator, b: Operator) -> Operator:
    return Operator(_sum(a.D, b.D), _sum(a.K, b.K))


def mul(a: Operator, b: Operator, W: np.ndarray) -> Operator:
    """The composition a after b."""
    D = None if a.D is None or b.D is None else a.D * b.D
    terms = []
    if a.D is not None and b.K is not None:
        terms.append(a.D[..., :, None] * b.K)
    if a.K is not None and b.D is not None:
        terms.append(a.K * b.D[..., None, :])
    if a.K is not None and b.K is not None:
        terms.append((a.K * W[..., None, :]) @ b.K)
    K = None
    for t in terms:
        K = t if K is None else K + t
    return Operator(D, K)


def inverse_one_minus(a: Operator, W: np.ndarray, shape) -> Operator:
    """(I - a)^-1 (a's delta part must stay below 1: energy leaves every bounce)."""
    G = np.ones(shape) if a.D is None else 1.0 / (1.0 - a.D)
    if a.K is None:
        return Operator(G, None)
    GK = G[..., :, None] * a.K
    n = GK.shape[-1]
    system = np.eye(n) - GK * W[..., None, :]
    X = np.linalg.solve(system, GK)
    return Operator(G, X * G[..., None, :])


@dataclass(frozen=True)
class Layer:
    """The four operators of a layer: reflection from the top (Rt) and from the bottom
    (Rb), transmission downward (Td) and upward (Tu); all on the same nodes."""

    Rt: Operator
    Td: Operator
    Rb: Operator
    Tu: Operator


def stack(top: Layer, bottom: Layer, W: np.ndarray, shape) -> Layer:
    """Adding equations: `top` lying on `bottom`, all orders of multiple reflection
    between them summed by the two inverses."""
    down = inverse_one_minus(mul(top.Rb, bottom.Rt, W), W, shape)   # (I - Rb1 Rt2)^-1
    up = inverse_one_minus(mul(bottom.Rt, top.Rb, W), W, shape)     # (I - Rt2 Rb1)^-1
    Td = mul(bottom.Td, mul(down, top.Td, W), W)
    Tu = mul(top.Tu, mul(up, bottom.Tu, W), W)
    Rt = add(top.Rt, mul(top.Tu, mul(up, mul(bottom.Rt, top.Td, W), W), W))
    Rb = add(bottom.Rb, mul(bottom.Td, mul(down, mul(top.Rb, bottom.Tu, W), W), W))
    return Layer(Rt, Td, Rb, Tu)


def double(layer: Layer, W: np.ndarray, shape) -> Layer:
    """A homogeneous, up-down symmetric layer stacked on itself (Rt = Rb, Td = Tu)."""
    S = inverse_one_minus(mul(layer.Rt, layer.Rt, W), W, shape)
    ST = mul(S, layer.Td, W)
    T = mul(layer.Td, ST, W)
    R = add(layer.Rt, mul(layer.Td, mul(S, mul(layer.Rt, layer.Td, W), W), W))
    return Layer(R, T, R, T)


def _sum(x, y):
    if x is None:
        return y
    if y is None:
        return x
    return x + y
