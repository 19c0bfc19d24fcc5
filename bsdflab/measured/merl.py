"""``Merl``: a MERL BRDF database file (Matusik, Pfister, Brand & McMillan 2003, "A
Data-Driven Reflectance Model") as a bsdflab BSDF.

File layout (little-endian), as documented with the dataset's reader ``BRDFRead.cpp``:
three int32 dimensions (90, 90, 180) -- theta_h, theta_d, phi_d -- then 3 x 90 x 90 x 180
float64 values, all red, then green, then blue, phi_d fastest. Values times the scales
(1/1500, 1.15/1500, 1.66/1500) are f in 1/sr, linear RGB. The half/difference angles are
Rusinkiewicz's (1998); theta_h is stored on a square-root grid (index = sqrt(theta_h /
90 deg) * 90), phi_d over [0, 180) deg by reciprocity. Lookup is nearest-cell, as the
dataset's reader. The dataset marks unmeasured cells with negative values: they read as 0.
Sampling is cosine-weighted. Evaluated by the C++ core (``MerlBSDF``, usable by the
renderer); ``reference`` is the same lookup in numpy, for cross-checks.
"""
from __future__ import annotations

import os
from typing import Any

import numpy as np

from bsdflab import _core
from bsdflab.bsdfs.base import BSDF
from bsdflab.lobes import Lobe
from bsdflab.measured import store

DIMS = (90, 90, 180)
SCALES = np.array([1.0 / 1500.0, 1.15 / 1500.0, 1.66 / 1500.0])


MAX_F = 1e12   # 1/sr: far above any measured peak (and an index-valued test file), far below float32's 3.4e38


def read_merl(path) -> np.ndarray:
    """The (3, 90, 90, 180) array of f values (1/sr, scales applied, negatives as 0)."""
    path = os.fspath(path)
    try:
        with open(path, "rb") as f:
            raw = f.read(12 + 8 * 3 * int(np.prod(DIMS)) + 1)
    except OSError as e:
        raise ValueError(f"{path}: cannot read the MERL file ({e.strerror})") from None
    if len(raw) < 12:
        raise ValueError(f"{path}: truncated MERL file (no dimensions header)")
    dims = tuple(int(d) for d in np.frombuffer(raw[:12], dtype="<i4"))
    if dims != DIMS:
        raise ValueError(f"{path}: MERL dimensions {dims}, expected {DIMS} (theta_h, theta_d, phi_d)")
    expect = 12 + 8 * 3 * int(np.prod(DIMS))
    if len(raw) != expect:
        raise ValueError(f"{path}: MERL values must be {expect - 12} bytes after the header, "
                         f"got {len(raw) - 12} (truncated or padded)")
    values = np.frombuffer(raw[12:], dtype="<f8").reshape(3, *DIMS)
    if not np.all(np.isfinite(values)):
        raise ValueError(f"{path}: MERL values hold NaN or infinity")
    f = np.maximum(values, 0.0) * SCALES[:, None, None, None]
    if f.max() > MAX_F:
        raise ValueError(f"{path}: MERL values reach f = {f.max():.3g}/sr, beyond any reflectance (at most "
                         f"{MAX_F:g}/sr; the core evaluates in float32)")
    return f


def merl_bytes(values: np.ndarray) -> bytes:
    """The file bytes for f values (3, 90, 90, 180) in 1/sr (inverse of ``read_merl``)."""
    v = np.asarray(values, dtype=np.float64)
    if v.shape != (3, *DIMS):
        raise ValueError(f"values must have shape {(3, *DIMS)}, got {v.shape}")
    return np.array(DIMS, dtype="<i4").tobytes() + (v / SCALES[:, None, None, None]).astype("<f8").tobytes()


def half_diff(wi: np.ndarray, wo: np.ndarray):
    """Rusinkiewicz's (theta_h, theta_d, phi_d) of direction pairs (N, 3)."""
    h = wi + wo
    h = h / np.maximum(np.linalg.norm(h, axis=1, keepdims=True), 1e-300)
    theta_h = np.arccos(np.clip(h[:, 2], -1, 1))
    phi_h = np.arctan2(h[:, 1], h[:, 0])
    c, s = np.cos(-phi_h), np.sin(-phi_h)
    x, y = c * wi[:, 0] - s * wi[:, 1], s * wi[:, 0] + c * wi[:, 1]
    z = wi[:, 2]
    ct, st = np.cos(-theta_h), np.sin(-theta_h)
    dx, dz = ct * x + st * z, -st * x + ct * z
    theta_d = np.arccos(np.clip(dz, -1, 1))
    phi_d = np.arctan2(y, dx)
    return theta_h, theta_d, phi_d


class _MerlModel:
    """The nearest-cell lookup in numpy (f cos theta_o), the C++ core's cross-check."""

    def __init__(self, values):
        self.values = values

    def eval(self, wi, wo):
        th, td, pd = half_diff(wi, wo)
        ih = np.clip((np.sqrt(np.clip(th / (np.pi / 2), 0, 1)) * 90).astype(int), 0, 89)
        idd = np.clip((td / (np.pi / 2) * 90).astype(int), 0, 89)
        pd = np.where(pd < 0, pd + np.pi, pd)
        ip = np.clip((pd / np.pi * 180).astype(int), 0, 179)
        f = self.values[:, ih, idd, ip].T
        active = (wi[:, 2] > 0) & (wo[:, 2] > 0)
        return np.where(active[:, None], f * np.maximum(wo[:, 2], 0)[:, None], 0.0)


class Merl(BSDF):
    """A MERL database BRDF (RGB, isotropic, reflection only).

    Parameters
    ----------
    path : str or path
        A ``.binary`` file of the MERL database; read and checked at once.
    hash : str
        Instead of ``path``: the SHA-256 of a file kept in a store folder
        (bsdflab.measured.store; the service's uploads); the model's dict then names it by
        this hash, never by a path.
    """

    type_name = "merl"
    # Its dict names a file on this machine: an HTTP request must never carry it (the service
    # resolves measured files by artefact hash; see docs/measured.md).
    reads_path = True

    def __init__(self, path=None, hash=None):   # noqa: A002 -- the dict's key
        super().__init__()
        if (path is None) == (hash is None):
            raise ValueError("give exactly one of path (a file) or hash (a stored upload's SHA-256)")
        self.hash = hash
        if hash is not None:
            path = store.locate(hash, ".binary", "MERL .binary file")
        if not isinstance(path, (str, os.PathLike)):
            raise ValueError(f"path must be the path of a MERL .binary file, got {type(path).__name__}")
        self.path = os.fspath(path)
        self.values = read_merl(self.path)
        self.reference = _MerlModel(self.values)

    @property
    def lobes(self) -> Lobe:
        return Lobe.GLOSSY_REFLECTION

    def _channels(self, wavelengths):
        if wavelengths is not None:
            raise ValueError("MERL files store RGB; wavelengths must be None")
        return np.arange(3, dtype=float), None

    def _build(self, wavelengths):
        return _core.MerlBSDF(np.ascontiguousarray(self.values, dtype=np.float32).ravel())

    def render_core(self):
        return self._core(np.arange(3, dtype=float)), None

    def _params(self) -> dict[str, Any]:
        return {"path": self.path} if self.hash is None else {"hash": self.hash}
