"""Adaptive Chebyshev interpolation of smooth vector-valued functions on an interval.

tmm's transfer-matrix solver takes one angle per call; the oracle needs its results at
arbitrary, many angles. A Chebyshev interpolant through tmm's values turns it into a
vectorised function with an a-posteriori error bound: each refinement triples the
first-kind Chebyshev points (the old ones are a subset, so no sample is wasted) and the
previous interpolant is compared with the new samples.

The sampled function may report where it was *actually* evaluated (tmm rounds its
angles, see ``_interface``); the interpolant then passes through those abscissae (a
Chebyshev-Vandermonde solve, well conditioned for points this close to Chebyshev's).
"""
from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.polynomial import chebyshev

TOLERANCE = 1e-13   # absolute; the interpolated quantities are powers in [0, 1]
FIRST_POINTS = 9
MAX_POINTS = 3 ** 7

Sampler = Callable[[np.ndarray], "tuple[np.ndarray, np.ndarray]"]


def _nodes(n: int) -> np.ndarray:
    """First-kind Chebyshev points on [-1, 1]."""
    return np.cos((2 * np.arange(n) + 1) * np.pi / (2 * n))


class Chebyshev:
    """Interpolant of a sampled function on [a, b], refined until it predicts every new
    sample to within ``tol``.

    Parameters
    ----------
    sampler : callable
        Maps nominal points t (M,) inside (a, b) to (t_actual (M,), values (M, K)):
        where the function was really evaluated (t itself if exact) and its values there.
    a, b : float
        The interval.
    tol : float
        Absolute accuracy goal for every component.

    Raises
    ------
    RuntimeError
        When ``MAX_POINTS`` points do not reach ``tol`` (a function far from smooth).
    """

    def __init__(self, sampler: Sampler, a: float, b: float, tol: float = TOLERANCE):
        self.a, self.b = float(a), float(b)
        n = FIRST_POINTS
        x, values = self._sample(sampler, _nodes(n))
        coef = self._fit(x, values)
        while True:
            nominal = _nodes(3 * n)
            new = np.arange(3 * n) % 3 != 1           # index 3k+1 is the old point k
            x_new, fresh = self._sample(sampler, nominal[new])
            miss = float(np.max(np.abs(chebyshev.chebval(x_new, coef).T - fresh)))
            xs, merged = np.empty(3 * n), np.empty((3 * n,) + values.shape[1:])
            xs[~new], xs[new] = x, x_new
            merged[~new], merged[new] = values, fresh
            x, values, n = xs, merged, 3 * n
            coef = self._fit(x, values)
            if miss <= tol:
                break
            if n >= MAX_POINTS:
                raise RuntimeError(f"Chebyshev interpolation did not reach {tol:g} with "
                                   f"{n} points (last miss {miss:.3g})")
        self.coef = coef
        self.points = n
        self.miss = miss  # error of the previous, coarser interpolant at the new points

    def _sample(self, sampler, x_nominal):
        t_actual, values = sampler(self._to_t(x_nominal))
        x = (2.0 * np.asarray(t_actual, dtype=np.float64) - (self.a + self.b)) / (self.b - self.a)
        return x, np.asarray(values, dtype=np.float64)

    @staticmethod
    def _fit(x, values):
        return np.linalg.solve(chebyshev.chebvander(x, len(x) - 1), values)

    def _to_t(self, x):
        return self.a + (self.b - self.a) * 0.5 * (x + 1.0)

    def __call__(self, t) -> np.ndarray:
        """Values at t (M,), shape (M, K)."""
        x = (2.0 * np.asarray(t, dtype=np.float64) - (self.a + self.b)) / (self.b - self.a)
        return np.atleast_2d(chebyshev.chebval(x, self.coef)).T.reshape(len(x), -1)
