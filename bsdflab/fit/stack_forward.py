"""Specular rows of a dataset from a structure seen through an instrument.

``StackForward(dataset, structure)`` compiles the rows (unique angles x unique wavelengths)
once; ``evaluate(value, scale)`` computes, per parameter set, the media's complex indices at
the bandwidth's Gauss-Hermite wavelengths (numpy, vectorised over sets), hands them to the
C++ core (``_core.InstrumentStack``: the stack's reflectance via film_stack, the cone and
slit averages, GIL released) and applies scale and background.
"""
from __future__ import annotations

import numpy as np

from bsdflab import _core
from bsdflab.fit.data import GEOMETRIES, Dataset
from bsdflab.fit.structure import Structure

BANDWIDTH_NODES = 7      # Gauss-Hermite nodes of the slit function (odd: the middle one is the nominal wavelength)
CONE_NODES = 4           # Gauss-Legendre nodes over the cone's polar angle
CONE_AZIMUTHS = 6        # midpoint nodes over the cone's azimuth in [0, pi]
FWHM_TO_SIGMA = 1.0 / (2.0 * np.sqrt(2.0 * np.log(2.0)))


class StackForward:
    def __init__(self, dataset: Dataset, structure: Structure, bandwidth_nodes: int = BANDWIDTH_NODES,
                 cone_nodes: int = CONE_NODES, cone_azimuths: int = CONE_AZIMUTHS):
        bad = dataset.geometry != GEOMETRIES.index("specular")
        if np.any(bad):
            i = int(np.argmax(bad))
            raise ValueError(f"row {i}: the stack model predicts specular rows only, got a "
                             f"{GEOMETRIES[dataset.geometry[i]]} row (use the snake model for diffuse/total/brdf)")
        if bandwidth_nodes % 2 == 0 or not 1 <= bandwidth_nodes <= 63:
            raise ValueError(f"bandwidth_nodes must be odd, in [1, 63], got {bandwidth_nodes}")
        if not 1 <= cone_nodes <= 64 or not 1 <= cone_azimuths <= 64:
            raise ValueError(f"cone_nodes and cone_azimuths must lie in [1, 64], got {cone_nodes}, {cone_azimuths}")
        self.dataset, self.structure = dataset, structure
        self.angles, self._ai = np.unique(dataset.angle_deg, return_inverse=True)
        self.wavelengths, self._wi = np.unique(dataset.wavelength_nm, return_inverse=True)
        self._x, w = np.polynomial.hermite.hermgauss(bandwidth_nodes)
        self._x[bandwidth_nodes // 2] = 0.0
        u, cw = np.polynomial.legendre.leggauss(cone_nodes)
        self._core = _core.InstrumentStack(self.angles, len(self.wavelengths), len(structure.order), w,
                                           0.5 * (u + 1.0), 0.5 * cw, cone_azimuths)

    @property
    def rows(self) -> int:
        return len(self.dataset)

    def exact(self, value, offset, acceptance, bandwidth) -> np.ndarray:
        """The smeared reflectance (P, rows) before scale and background."""
        bandwidth = np.asarray(bandwidth, float)
        sigma = np.where(np.isfinite(bandwidth), bandwidth, 0.0) * FWHM_TO_SIGMA
        # wavelength-major: column j * B + k is lambda_j + sqrt(2) sigma x_k
        wl = (self.wavelengths[None, :, None] + np.sqrt(2.0) * sigma[:, None, None] * self._x[None, None, :])
        wl = wl.reshape(len(sigma), -1)
        n, d = self.structure.arrays(value, wl)
        inst = np.column_stack([offset, acceptance, bandwidth]).astype(float)
        out = self._core.evaluate(np.ascontiguousarray(n), np.ascontiguousarray(wl), np.ascontiguousarray(d, float),
                                  np.ascontiguousarray(inst))
        return out[:, self._ai, self._wi]

    def evaluate(self, value, scale, background, offset, acceptance, bandwidth) -> np.ndarray:
        """Reported values (P, rows): scale (P,) or (P, rows), the others (P,)."""
        r = self.exact(value, offset, acceptance, bandwidth)
        scale = np.asarray(scale, float)
        scale = scale[:, None] if scale.ndim == 1 else scale
        return scale * r + np.asarray(background, float)[:, None]
