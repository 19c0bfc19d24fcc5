"""Specular rows of a dataset from a structure seen through an instrument.

``StackForward(dataset, structure)`` compiles the rows (unique angles x unique wavelengths)
once; ``evaluate(value, scale)`` computes, per parameter set, the media's complex indices at
the bandwidth's Gauss-Hermite wavelengths (numpy, vectorised over sets), hands them to the
C++ core (``_core.InstrumentStack``: the stack's reflectance via film_stack, the cone and
slit averages, GIL released) and applies scale and background.

The slit has two quadratures. Evenly spaced wavelengths (step h) and a slit of sd
sigma >= 1.2 h / 4 take the fast one: R on a grid of step h / m (m = ceil(1.2 h / sigma) <= 4)
that every row's kernel shares, then a sampled Gaussian in C++ (_core.smear_uniform; the
trapezoid rule, error ~exp(-2 pi^2 (sigma m / h)^2) < 1e-12): about W m + 9 sigma m / h
stack evaluations instead of W x bandwidth_nodes. Otherwise Gauss-Hermite nodes per row.
"""
from __future__ import annotations

import numpy as np

from bsdflab import _core
from bsdflab.fit.data import GEOMETRIES, Dataset
from bsdflab.fit.structure import Structure
from bsdflab.fit.thickness_spread import THICKNESS_NODES, spread_average

GRID_SIGMA_STEPS = 1.2   # the shared grid's step is at most sigma / 1.2
GRID_MAX_REFINE = 4      # grid step >= h / 4; narrower slits use Gauss-Hermite
GRID_REACH_SIGMAS = 4.5  # kernel half-width (weights beyond: < 4e-5 of the peak, renormalised)

BANDWIDTH_NODES = 7      # Gauss-Hermite nodes of the slit function (odd: the middle one is the nominal wavelength)
CONE_NODES = 4           # Gauss-Legendre nodes over the cone's polar angle
CONE_AZIMUTHS = 6        # midpoint nodes over the cone's azimuth in [0, pi]
FWHM_TO_SIGMA = 1.0 / (2.0 * np.sqrt(2.0 * np.log(2.0)))


def slit_nodes(n: int = BANDWIDTH_NODES) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Hermite nodes x and weights of the Gaussian slit (n odd: the middle node is set
    to exactly 0, the nominal wavelength): R(lambda) ~ sum_k w_k R(lambda + sqrt(2) sigma x_k) / sum w."""
    x, w = np.polynomial.hermite.hermgauss(n)
    x[n // 2] = 0.0
    return x, w


def cone_polar_nodes(n: int = CONE_NODES) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre nodes u and weights on [0, 1] of the cone angle b / a (times sin b for
    solid angle where used)."""
    u, w = np.polynomial.legendre.leggauss(n)
    return 0.5 * (u + 1.0), 0.5 * w


class StackForward:
    def __init__(self, dataset: Dataset, structure: Structure, bandwidth_nodes: int = BANDWIDTH_NODES,
                 cone_nodes: int = CONE_NODES, cone_azimuths: int = CONE_AZIMUTHS,
                 thickness_nodes: int = THICKNESS_NODES):
        bad = dataset.geometry != GEOMETRIES.index("specular")
        if np.any(bad):
            i = int(np.argmax(bad))
            raise ValueError(f"row {i}: the stack model predicts specular rows only, got a "
                             f"{GEOMETRIES[dataset.geometry[i]]} row (use the snake model for diffuse/total/brdf)")
        if bandwidth_nodes % 2 == 0 or not 1 <= bandwidth_nodes <= 63:
            raise ValueError(f"bandwidth_nodes must be odd, in [1, 63], got {bandwidth_nodes}")
        if not 1 <= cone_nodes <= 64 or not 1 <= cone_azimuths <= 64:
            raise ValueError(f"cone_nodes and cone_azimuths must lie in [1, 64], got {cone_nodes}, {cone_azimuths}")
        if not 1 <= thickness_nodes <= 64:
            raise ValueError(f"thickness_nodes must lie in [1, 64], got {thickness_nodes}")
        self.thickness_nodes = int(thickness_nodes)
        self.dataset, self.structure = dataset, structure
        self.angles, self._ai = np.unique(dataset.angle_deg, return_inverse=True)
        self.wavelengths, self._wi = np.unique(dataset.wavelength_nm, return_inverse=True)
        self._x, w = slit_nodes(bandwidth_nodes)
        self._cone = (*cone_polar_nodes(cone_nodes), cone_azimuths)
        self._core = _core.InstrumentStack(self.angles, len(self.wavelengths), len(structure.order), w,
                                           *self._cone)
        steps = np.diff(self.wavelengths)
        self._step = (float(steps.mean()) if len(steps) and np.allclose(steps, steps[0], rtol=1e-9, atol=0)
                      else None)
        self._grid_cores: dict[int, object] = {}

    @property
    def rows(self) -> int:
        return len(self.dataset)

    def exact(self, value, offset, acceptance, bandwidth) -> np.ndarray:
        """The smeared reflectance (P, rows) before scale and background, averaged over the
        layers' thickness spreads (bsdflab.fit.thickness_spread: each set's thickness nodes
        go through the instrument as extra sets, in calls of bounded size)."""
        def smeared(v, index):
            inst = (np.atleast_1d(np.asarray(a, float))[index] for a in (offset, acceptance, bandwidth))
            return self._smeared(v, *inst)
        # values one set costs: the spectrum per angle at its slit nodes (the shared grid is smaller)
        per_set = len(self.angles) * len(self.wavelengths) * len(self._x)
        return spread_average(self.structure, value, smeared, self.thickness_nodes, per_set)

    def _smeared(self, value, offset, acceptance, bandwidth) -> np.ndarray:
        bandwidth = np.asarray(bandwidth, float)
        sigma = np.where(np.isfinite(bandwidth), bandwidth, 0.0) * FWHM_TO_SIGMA
        if self._step is not None and len(sigma) and np.all(sigma > 0):
            refine = int(np.ceil(GRID_SIGMA_STEPS * self._step / sigma.min()))
            if refine <= GRID_MAX_REFINE:
                return self._exact_on_grid(value, offset, acceptance, sigma, refine)
        # wavelength-major: column j * B + k is lambda_j + sqrt(2) sigma x_k
        wl = (self.wavelengths[None, :, None] + np.sqrt(2.0) * sigma[:, None, None] * self._x[None, None, :])
        wl = wl.reshape(len(sigma), -1)
        n, d = self.structure.arrays(value, wl)
        inst = np.column_stack([offset, acceptance, bandwidth]).astype(float)
        out = self._core.evaluate(np.ascontiguousarray(n), np.ascontiguousarray(wl), np.ascontiguousarray(d, float),
                                  np.ascontiguousarray(inst))
        return out[:, self._ai, self._wi]

    def _exact_on_grid(self, value, offset, acceptance, sigma, refine) -> np.ndarray:
        delta = self._step / refine
        reach = int(np.ceil(GRID_REACH_SIGMAS * sigma.max() / delta))
        size = (len(self.wavelengths) - 1) * refine + 1 + 2 * reach
        core = self._grid_cores.get(size)
        if core is None:
            core = _core.InstrumentStack(self.angles, size, len(self.structure.order), [1.0], *self._cone)
            self._grid_cores = {size: core}   # one kept: the batch's sigma range moves slowly
        grid = self.wavelengths[0] + delta * (np.arange(size) - reach)
        wl = np.repeat(grid[None, :], len(sigma), axis=0)
        n, d = self.structure.arrays(value, wl)
        inst = np.column_stack([offset, acceptance, np.zeros(len(sigma))]).astype(float)
        r = core.evaluate(np.ascontiguousarray(n), wl, np.ascontiguousarray(d, float), np.ascontiguousarray(inst))
        out = _core.smear_uniform(r, np.ascontiguousarray(sigma), delta, reach, refine, len(self.wavelengths), reach)
        return out[:, self._ai, self._wi]

    def evaluate(self, value, scale, background, offset, acceptance, bandwidth) -> np.ndarray:
        """Reported values (P, rows): scale (P,) or (P, rows), the others (P,)."""
        r = self.exact(value, offset, acceptance, bandwidth)
        scale = np.asarray(scale, float)
        scale = scale[:, None] if scale.ndim == 1 else scale
        return scale * r + np.asarray(background, float)[:, None]
