"""The core-object face (``eval`` / ``pdf`` / ``sample`` on numpy arrays, ``lobes``,
``channels``) of a measured material evaluated in numpy, so ``bsdflab.BSDF`` can drive it
like a C++ core object. Vectorised over queries; no Python loop per sample."""
from __future__ import annotations

import numpy as np

from bsdflab.lobes import Lobe


class NumpyCore:
    """Adapts ``model`` (eval(wi, wo) -> (N, C), pdf(wi, wo), sample(wi, u2) -> (wo, weight,
    pdf)) with lobe ``lobe`` (one Lobe bit) to the calls ``bsdflab.BSDF`` makes."""

    def __init__(self, model, channels: int, lobe: Lobe):
        self.model, self.channels, self.lobes = model, int(channels), int(lobe)

    def _on(self, mask) -> bool:
        return bool(int(mask) & self.lobes)

    def eval(self, wi, wo, mask, thickness=None):
        if not self._on(mask):
            return np.zeros((len(wi), self.channels))
        return np.nan_to_num(self.model.eval(_unit(wi), _unit(wo)), nan=0.0, posinf=0.0, neginf=0.0)

    def pdf(self, wi, wo, mask, thickness=None):
        if not self._on(mask):
            return np.zeros(len(wi))
        return np.nan_to_num(self.model.pdf(_unit(wi), _unit(wo)), nan=0.0, posinf=0.0, neginf=0.0)

    def sample(self, wi, u1, u2, mask, thickness=None):
        n = len(wi)
        if not self._on(mask):
            z = np.zeros((n, 3))
            return z, np.zeros((n, self.channels)), np.zeros(n), np.zeros(n, dtype=np.uint32), np.ones(n)
        wo, weight, pdf = self.model.sample(_unit(wi), np.asarray(u2, float))
        ok = (pdf > 0) & np.all(np.isfinite(weight), axis=1) & np.all(np.isfinite(wo), axis=1)
        wo = np.where(ok[:, None], wo, 0.0)
        weight = np.where(ok[:, None], weight, 0.0)
        lobe = np.where(ok, self.lobes, 0).astype(np.uint32)
        return wo, weight, np.where(ok, pdf, 0.0), lobe, np.ones(n)


def _unit(v):
    """Normalised copies; NaN / zero-length rows become (0, 0, -1) (below: answers zero)."""
    v = np.asarray(v, dtype=np.float64)
    norm = np.linalg.norm(v, axis=1, keepdims=True)
    bad = ~np.isfinite(norm[:, 0]) | (norm[:, 0] == 0)
    out = np.where(bad[:, None], np.array([0.0, 0.0, -1.0]), v / np.where(bad[:, None], 1.0, norm))
    return out
