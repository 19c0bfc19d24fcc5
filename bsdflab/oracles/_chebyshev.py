"""Adaptive Chebyshev interpolation of smooth vector-valued functions on an interval.

tmm's transfer-matrix solver takes one angle per call; the oracle needs its results at
arbitrary, many angles. A Chebyshev interpolant through tmm's values at first-kind
Chebyshev points turns it into a vectorised function with an a-posteriori error bound:
each refinement triples the points (the old ones are a subset, so no sample is wasted)
and the previous interpolant is compared with the new samples. The comparison allows
for a known noise level of the samples (``noise``), so that noisy but correct samples do
not drive the refinement on forever.
"""
from __future__ import annotations

from typing import Callable

import numpy as np
from numpy.polynomial import chebyshev

TOLERANCE = 1e-13   # absolute; the interpolated quantities are powers in [0, 1]
FIRST_POINTS = 9
MAX_POINTS = 3 ** 7


def _angles(n: int) -> np.ndarray:
    return (2 * np.arange(n) + 1) * np.pi / (2 * n)


def _coefficients(values: np.ndarray) -> np.ndarray:
    """Chebyshev coefficients (n, K) of the interpolant through (n, K) values at the
    first-kind points (a discrete cosine transform)."""
    n = len(values)
    basis = np.cos(np.outer(np.arange(n), _angles(n)))  # (j, k): T_j at point k
    coef = (2.0 / n) * basis @ values
    coef[0] *= 0.5
    return coef


class Chebyshev:
    """Interpolant of ``func`` on [a, b], refined until it is within ``tol`` of the
    function at every refinement point.

    Parameters
    ----------
    func : callable
        Maps points t of shape (M,) to values of shape (M, K); called only inside (a, b).
    a, b : float
        The interval.
    tol : float
        Absolute accuracy goal for every component.
    noise : callable, optional
        Absolute error bound of the samples themselves at points t (M,) -> (M,); the
        refinement test is |interpolant - sample| <= tol + noise(t).

    Raises
    ------
    RuntimeError
        When ``MAX_POINTS`` points do not reach ``tol`` (a function far from smooth).
    """

    def __init__(self, func: Callable[[np.ndarray], np.ndarray], a: float, b: float,
                 tol: float = TOLERANCE,
                 noise: Callable[[np.ndarray], np.ndarray] | None = None):
        self.a, self.b = float(a), float(b)
        n = FIRST_POINTS
        values = np.asarray(func(self._to_t(np.cos(_angles(n)))), dtype=np.float64)
        coef = _coefficients(values)
        while True:
            x = np.cos(_angles(3 * n))
            new = np.arange(3 * n) % 3 != 1           # index 3k+1 is the old point k
            t_new = self._to_t(x[new])
            fresh = np.asarray(func(t_new), dtype=np.float64)
            allowed = tol + (noise(t_new) if noise is not None else 0.0)
            miss = np.abs(chebyshev.chebval(x[new], coef).T - fresh).max(axis=1)
            ratio = float(np.max(miss / allowed))  # <= 1: within tolerance everywhere
            merged = np.empty((3 * n,) + values.shape[1:])
            merged[~new], merged[new] = values, fresh
            values, coef, n = merged, _coefficients(merged), 3 * n
            if ratio <= 1.0:
                break
            if n >= MAX_POINTS:
                raise RuntimeError(f"Chebyshev interpolation did not reach {tol:g} (plus "
                                   f"sample noise) with {n} points: {ratio:.3g} x over")
        self.coef = coef
        self.points = n

    def _to_t(self, x):
        return self.a + (self.b - self.a) * 0.5 * (x + 1.0)

    def __call__(self, t) -> np.ndarray:
        """Values at t (M,), shape (M, K)."""
        x = (2.0 * np.asarray(t, dtype=np.float64) - (self.a + self.b)) / (self.b - self.a)
        return np.atleast_2d(chebyshev.chebval(x, self.coef)).T.reshape(len(x), -1)
