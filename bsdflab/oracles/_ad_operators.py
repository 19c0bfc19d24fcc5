r"""Scattering operators of the adding-doubling oracle and the adding equations.

Discretisation. Radiance on one hemisphere of the slab medium is a vector over cosine
nodes mu_j with quadrature weights w_j. Azimuth is expanded in a cosine series of the
propagation-azimuth difference, f = sum_m f^m(mu_out, mu_in) cos(m dphi). Order m of an
operator acts as

    (O L)_i = D_i L_i + sum_j K_ij W_j L_j,    W_j = pi (1 + [m = 0]) mu_j w_j,

where D is its delta part (unscattered transmission, specular reflection: the same in
every order) and K its kernel (the Fourier coefficient of f; output row, input column).
Keeping D and K apart makes products and inverses exact for any extra cosines:

    (D1 + K1 W)(D2 + K2 W) = D1 D2 + (D1 K2 + K1 D2 + K1 W K2) W,
    (I - D - K W)^-1       = G + (X G) W,   G = (I - D)^-1,   X = (I - G K W)^-1 G K.

Query cosines (Nystrom extension). The directions a caller asks about are extra nodes of
weight zero: light enters at "input" cosines and leaves at "output" cosines. Weight zero
means they never feed back into the nodes, so an operator is carried as its node block
K (n x n) plus the rows Kr (outputs x nodes), the columns Kc (nodes x inputs) and only
the requested (output, input) pairs Kp, with D at nodes, outputs (Dr) and inputs (Dc).
Every product and inverse below is the block form of the formulas above; the cost is
O(n^3 + (outputs + inputs) n^2 + pairs n) per order instead of O((n + queries)^3).

Arrays carry leading batch axes (wavelength, Fourier order); None means zero.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bsdflab.util.deprecation import renamed_attributes


@dataclass(frozen=True)
class Grid:
    """Nodes and queries: W (M, n); pairs (pr[k], pc[k]) index outputs and inputs."""

    W: np.ndarray
    pr: np.ndarray
    pc: np.ndarray
    batch: tuple       # (L, M)
    n: int
    n_out: int
    n_in: int


@dataclass(frozen=True)
class Operator:
    D: np.ndarray | None = None    # (..., n)
    Dr: np.ndarray | None = None   # (..., outputs)
    Dc: np.ndarray | None = None   # (..., inputs)
    K: np.ndarray | None = None    # (..., n, n)
    Kr: np.ndarray | None = None   # (..., outputs, n)
    Kc: np.ndarray | None = None   # (..., n, inputs)
    Kp: np.ndarray | None = None   # (..., pairs)


def identity(g: Grid) -> Operator:
    return Operator(np.ones(g.n), np.ones(g.n_out), np.ones(g.n_in))


def add(a: Operator, b: Operator) -> Operator:
    return Operator(*(_total(x, y) for x, y in zip(_fields(a), _fields(b))))


def mul(a: Operator, b: Operator, g: Grid) -> Operator:
    """The composition a after b."""
    W = g.W
    return Operator(
        _prod(a.D, b.D), _prod(a.Dr, b.Dr), _prod(a.Dc, b.Dc),
        _total(_rows(a.D, b.K), _cols(a.K, b.D), _kwk(a.K, W, b.K)),
        _total(_rows(a.Dr, b.Kr), _cols(a.Kr, b.D), _kwk(a.Kr, W, b.K)),
        _total(_rows(a.D, b.Kc), _cols(a.Kc, b.Dc), _kwk(a.K, W, b.Kc)),
        _total(_prod(_take(a.Dr, g.pr), b.Kp), _prod(a.Kp, _take(b.Dc, g.pc)),
               _pairs(a.Kr, W, b.Kc, g)))


def inverse_one_minus(a: Operator, g: Grid) -> Operator:
    """(I - a)^-1 (a's delta part must stay below 1: energy leaves every bounce)."""
    G, Gr, Gc = (np.ones(n) if d is None else 1.0 / (1.0 - d)
                 for d, n in ((a.D, g.n), (a.Dr, g.n_out), (a.Dc, g.n_in)))
    if all(k is None for k in (a.K, a.Kr, a.Kc, a.Kp)):
        return Operator(G, Gr, Gc)
    L, M = g.batch
    K = _full(a.K, (L, M, g.n, g.n))
    Kr = _full(a.Kr, (L, M, g.n_out, g.n))
    Kc = _full(a.Kc, (L, M, g.n, g.n_in))
    Kp = _full(a.Kp, (L, M, len(g.pr)))
    GK = G[..., :, None] * K
    system = np.eye(g.n) - GK * g.W[..., None, :]
    solution = np.linalg.solve(system, np.concatenate([GK, G[..., :, None] * Kc], axis=-1))
    X, Xc = solution[..., :g.n], solution[..., g.n:]
    Xr = Gr[..., :, None] * (Kr + _kwk(Kr, g.W, X))
    Xp = _take(Gr, g.pr) * (Kp + _pairs(Kr, g.W, Xc, g))
    return Operator(G, Gr, Gc, X * G[..., None, :], Xr * G[..., None, :],
                    Xc * Gc[..., None, :], Xp * _take(Gc, g.pc))


@dataclass(frozen=True)
class LayerOperators:
    """The four operators of a layer: reflection from the top (Rt) and from the bottom
    (Rb), transmission downward (Td) and upward (Tu); all on the same grid."""

    Rt: Operator
    Td: Operator
    Rb: Operator
    Tu: Operator


def stack(top: LayerOperators, bottom: LayerOperators, g: Grid) -> LayerOperators:
    """Adding equations: `top` lying on `bottom`, all orders of multiple reflection
    between them summed by the two inverses."""
    down = inverse_one_minus(mul(top.Rb, bottom.Rt, g), g)   # (I - Rb1 Rt2)^-1
    up = inverse_one_minus(mul(bottom.Rt, top.Rb, g), g)     # (I - Rt2 Rb1)^-1
    Td = mul(bottom.Td, mul(down, top.Td, g), g)
    Tu = mul(top.Tu, mul(up, bottom.Tu, g), g)
    Rt = add(top.Rt, mul(top.Tu, mul(up, mul(bottom.Rt, top.Td, g), g), g))
    Rb = add(bottom.Rb, mul(bottom.Td, mul(down, mul(top.Rb, bottom.Tu, g), g), g))
    return LayerOperators(Rt, Td, Rb, Tu)


def double(layer: LayerOperators, g: Grid) -> LayerOperators:
    """A homogeneous, up-down symmetric layer stacked on itself (Rt = Rb, Td = Tu)."""
    S = inverse_one_minus(mul(layer.Rt, layer.Rt, g), g)
    T = mul(layer.Td, mul(S, layer.Td, g), g)
    R = add(layer.Rt, mul(layer.Td, mul(S, mul(layer.Rt, layer.Td, g), g), g))
    return LayerOperators(R, T, R, T)


# -- None-aware pieces ----------------------------------------------------------------
def _fields(o: Operator):
    return (o.D, o.Dr, o.Dc, o.K, o.Kr, o.Kc, o.Kp)


def _total(*terms):
    out = None
    for t in terms:
        if t is not None:
            out = t if out is None else out + t
    return out


def _prod(x, y):
    return None if x is None or y is None else x * y


def _take(d, idx):
    return None if d is None else d[..., idx]


def _rows(d, K):
    return None if d is None or K is None else d[..., :, None] * K


def _cols(K, d):
    return None if d is None or K is None else K * d[..., None, :]


def _kwk(A, W, B):
    return None if A is None or B is None else (A * W[..., None, :]) @ B


def _pairs(Ar, W, Bc, g: Grid):
    """sum_j Ar[pr_k, j] W_j Bc[j, pc_k] for every requested pair k."""
    if Ar is None or Bc is None or len(g.pr) == 0:
        return None
    return np.einsum("...kj,...jk->...k", (Ar * W[..., None, :])[..., g.pr, :], Bc[..., :, g.pc])


def _full(x, shape):
    return np.zeros(shape) if x is None else np.broadcast_to(x, shape)


# `Layer` was LayerOperators' name before issue 34 (FilmLayer is the optics' film layer).
__getattr__ = renamed_attributes(__name__, {"Layer": ("LayerOperators", LayerOperators)})
